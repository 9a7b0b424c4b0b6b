#include "core/signal/order_statistic.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace millwatch::signal {
namespace {

/// std::nth_element's answer, the independent truth.
double reference(std::vector<double> v, std::size_t k) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

void expect_every_rank(const std::vector<double>& v) {
  for (std::size_t k = 0; k < v.size(); ++k) {
    std::vector<double> copy = v;
    std::vector<double> scratch(v.size(), -1.0);
    ASSERT_EQ(kth_smallest(copy, k, scratch), reference(v, k)) << "k " << k << " of " << v.size();
  }
}

TEST(OrderStatistic, AgreesWithNthElementOnEveryRank) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::exponential_distribution<double> spread(1.0);  // magnitudes of noise: a long tail
  for (const std::size_t n : {1u, 2u, 3u, 7u, 8u, 9u, 15u, 16u, 17u, 100u, 701u}) {
    std::vector<double> v(n);
    for (auto& x : v) {
      x = spread(rng);
    }
    expect_every_rank(v);
    for (auto& x : v) {
      x = std::floor(4.0 * uniform(rng));  // many copies of few values
    }
    expect_every_rank(v);
  }
}

TEST(OrderStatistic, OrderedEqualAndSignedInputs) {
  std::vector<double> up(300), down(300), equal(300, 2.5), mixed(300);
  for (std::size_t i = 0; i < up.size(); ++i) {
    up[i] = static_cast<double>(i);
    down[i] = -static_cast<double>(i);
    mixed[i] = (i % 2 == 0 ? 1.0 : -1.0) * static_cast<double>(i % 37) + (i % 5 == 0 ? 0.0 : -0.0);
  }
  expect_every_rank(up);
  expect_every_rank(down);
  expect_every_rank(equal);
  expect_every_rank(mixed);
}

// A NaN is outside the contract (the tracker's magnitudes come from checked, filtered force),
// but must not hang the pipeline: a NaN pivot had left the range unchanged for ever. Every rank
// of sets with NaNs among ordinary values (at the pivot's places and elsewhere) returns a value
// of the set or a NaN.
TEST(OrderStatistic, ANanAmongTheValuesEndsTheSearch) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (const std::size_t n : {9U, 40U, 300U}) {
    for (const std::size_t at : {std::size_t{0}, n / 2, n - 1, n / 3}) {
      std::vector<double> v(n);
      for (double& x : v) {
        x = uniform(rng);
      }
      v[at] = nan;
      v[(at + 5) % n] = nan;
      for (std::size_t k = 0; k < n; ++k) {
        std::vector<double> copy = v, scratch(n);
        const double x = kth_smallest(copy, k, scratch);
        EXPECT_TRUE(std::isnan(x) || std::find(v.begin(), v.end(), x) != v.end()) << n << " " << k;
      }
    }
  }
}

}  // namespace
}  // namespace millwatch::signal
