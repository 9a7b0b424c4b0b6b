// An LCM udpm datagram read without LCM (msgs/lcm_datagram.hpp), on datagrams laid out as
// lcm_udpm.c's publish sends them: a short message's channel and payload, a fragment's header,
// and what is not a datagram LCM sends (cut short, another magic, a channel without its NUL or
// over LCM's 63 characters) — never read past the bytes (every prefix is parsed; ASan checks).
// That LCM's own sender gives these bytes is tested on the wire in tests/daemon/udpm_source_test.

#include "msgs/lcm_datagram.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace millwatch::messaging {
namespace {

void put32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) {
    b.push_back(static_cast<std::uint8_t>(v >> shift));
  }
}

void put16(std::vector<std::uint8_t>& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v >> 8));
  b.push_back(static_cast<std::uint8_t>(v));
}

std::vector<std::uint8_t> short_datagram(const std::string& channel,
                                         const std::vector<std::uint8_t>& payload,
                                         std::uint32_t sequence = 7) {
  std::vector<std::uint8_t> b;
  put32(b, 0x4c433032);  // "LC02"
  put32(b, sequence);
  b.insert(b.end(), channel.begin(), channel.end());
  b.push_back(0);
  b.insert(b.end(), payload.begin(), payload.end());
  return b;
}

std::vector<std::uint8_t> fragment(std::uint16_t number, std::uint16_t count,
                                   std::uint32_t message_bytes, const std::string& channel,
                                   const std::vector<std::uint8_t>& part) {
  std::vector<std::uint8_t> b;
  put32(b, 0x4c433033);  // "LC03"
  put32(b, 42);
  put32(b, message_bytes);
  put32(b, number == 0 ? 0 : 65487u * number - static_cast<std::uint32_t>(channel.size() + 1));
  put16(b, number);
  put16(b, count);
  if (number == 0) {
    b.insert(b.end(), channel.begin(), channel.end());
    b.push_back(0);
  }
  b.insert(b.end(), part.begin(), part.end());
  return b;
}

TEST(LcmDatagram, AShortMessageGivesItsChannelSequenceAndPayload) {
  const std::vector<std::uint8_t> payload{1, 2, 3, 0, 5};
  const auto bytes = short_datagram("MILLWATCH_FORCE_RAW", payload, 0x01020304);
  const LcmDatagram d = parse_lcm_datagram(bytes);
  ASSERT_EQ(d.kind, LcmDatagram::Kind::kShort);
  EXPECT_EQ(d.channel, "MILLWATCH_FORCE_RAW");
  EXPECT_EQ(d.sequence, 0x01020304u);
  EXPECT_EQ(std::vector<std::uint8_t>(d.payload.begin(), d.payload.end()), payload);
  // An empty payload is a message too (a zero-length publish).
  const auto empty = short_datagram("A", {});
  EXPECT_EQ(parse_lcm_datagram(empty).kind, LcmDatagram::Kind::kShort);
  EXPECT_TRUE(parse_lcm_datagram(empty).payload.empty());
}

TEST(LcmDatagram, AFragmentGivesItsPlaceAndOnlyTheFirstItsChannel) {
  const std::vector<std::uint8_t> part(100, 9);
  // The datagrams outlive their views.
  const auto first_bytes = fragment(0, 2, 70000, "RAW", part);
  const auto second_bytes = fragment(1, 2, 70000, "RAW", part);
  const LcmDatagram first = parse_lcm_datagram(first_bytes);
  ASSERT_EQ(first.kind, LcmDatagram::Kind::kFragment);
  EXPECT_EQ(first.channel, "RAW");
  EXPECT_EQ(first.sequence, 42u);
  EXPECT_EQ(first.message_bytes, 70000u);
  EXPECT_EQ(first.fragment, 0);
  EXPECT_EQ(first.fragments, 2);
  EXPECT_EQ(first.payload.size(), part.size());
  const LcmDatagram second = parse_lcm_datagram(second_bytes);
  ASSERT_EQ(second.kind, LcmDatagram::Kind::kFragment);
  EXPECT_TRUE(second.channel.empty());
  EXPECT_EQ(second.fragment, 1);
  EXPECT_EQ(second.payload.size(), part.size());
}

TEST(LcmDatagram, WhatLcmDoesNotSendIsNotTakenForAMessage) {
  using Kind = LcmDatagram::Kind;
  EXPECT_EQ(parse_lcm_datagram({}).kind, Kind::kNotLcm);
  auto other_magic = short_datagram("RAW", {1, 2});
  other_magic[3] = '3' + 1;  // "LC04"
  EXPECT_EQ(parse_lcm_datagram(other_magic).kind, Kind::kNotLcm);
  auto no_nul = short_datagram("RAW", {});
  no_nul.pop_back();  // the channel's NUL
  EXPECT_EQ(parse_lcm_datagram(no_nul).kind, Kind::kNotLcm);
  EXPECT_EQ(parse_lcm_datagram(short_datagram(std::string(63, 'C'), {1})).kind, Kind::kShort);
  EXPECT_EQ(parse_lcm_datagram(short_datagram(std::string(64, 'C'), {1})).kind, Kind::kNotLcm);
  auto cut_fragment = fragment(1, 2, 70000, "RAW", {});
  cut_fragment.pop_back();  // 19 of the 20 header bytes
  EXPECT_EQ(parse_lcm_datagram(cut_fragment).kind, Kind::kNotLcm);
}

TEST(LcmDatagram, EveryPrefixParsesWithinItsBytes) {
  for (const auto& whole : {short_datagram("MILLWATCH_FORCE_RAW", {1, 2, 3, 4}),
                            fragment(0, 3, 150000, "MILLWATCH_FORCE_RAW", {5, 6, 7})}) {
    for (std::size_t n = 0; n <= whole.size(); ++n) {
      // A copy of exactly n bytes: reading past it is a heap overflow ASan reports.
      const std::vector<std::uint8_t> prefix(whole.begin(), whole.begin() + static_cast<long>(n));
      const LcmDatagram d = parse_lcm_datagram(prefix);
      if (d.kind != LcmDatagram::Kind::kNotLcm) {
        EXPECT_LE(d.payload.data() + d.payload.size(), prefix.data() + prefix.size());
        EXPECT_GE(d.payload.data(), prefix.data());
      }
    }
  }
}

}  // namespace
}  // namespace millwatch::messaging
