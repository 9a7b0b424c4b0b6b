// Writes the hand-made seeds of fuzz_mat_cut_reader (tests/fuzz/corpus/mat_cut_reader) with
// libmatio: v5 vectors with a rate, v5 compressed N×3 single with a time vector, a v4 matrix
// (which the reader refuses), v7.3 vectors, a struct with fields, int16 rows. Not built by
// CMake; to remake the seeds:
//   c++ -std=c++20 -o /tmp/make_mat_seeds tests/fuzz/make_mat_seeds.cpp -lmatio
//   /tmp/make_mat_seeds tests/fuzz/corpus/mat_cut_reader

#include <matio.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace {

void put(mat_t* mat, const char* name, matio_classes c, matio_types t, std::size_t rows,
         std::size_t cols, void* data, matio_compression z = MAT_COMPRESSION_NONE) {
  std::size_t dims[2] = {rows, cols};
  matvar_t* v = Mat_VarCreate(name, c, t, 2, dims, data, 0);
  Mat_VarWrite(mat, v, z);
  Mat_VarFree(v);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : ".";
  const std::size_t n = 24;
  std::vector<double> fx(n), fy(n), fz(n), t(n), m(3 * n);
  std::vector<float> single(3 * n);
  std::vector<std::int16_t> counts(3 * n);
  for (std::size_t i = 0; i < n; ++i) {
    fx[i] = std::sin(0.5 * static_cast<double>(i));
    fy[i] = std::cos(0.5 * static_cast<double>(i));
    fz[i] = 0.1 * static_cast<double>(i);
    t[i] = 2.0 + static_cast<double>(i) * 2e-5;
    for (std::size_t c = 0; c < 3; ++c) {
      m[c * n + i] = (c == 0 ? fx : c == 1 ? fy : fz)[i];
      single[c * n + i] = static_cast<float>(m[c * n + i]);
      counts[i * 3 + c] = static_cast<std::int16_t>(1000 * m[c * n + i]);
    }
  }
  t[7] = NAN;     // a damaged time
  t[20] += 1e-4;  // a gap
  double rate = 50000.0;
  {
    mat_t* mat = Mat_CreateVer((dir + "/v5_vectors.mat").c_str(), nullptr, MAT_FT_MAT5);
    put(mat, "Fx", MAT_C_DOUBLE, MAT_T_DOUBLE, n, 1, fx.data());
    put(mat, "Fy", MAT_C_DOUBLE, MAT_T_DOUBLE, n, 1, fy.data());
    put(mat, "Fz", MAT_C_DOUBLE, MAT_T_DOUBLE, 1, n, fz.data());
    put(mat, "fs", MAT_C_DOUBLE, MAT_T_DOUBLE, 1, 1, &rate);
    Mat_Close(mat);
  }
  {
    mat_t* mat = Mat_CreateVer((dir + "/v5z_matrix_time.mat").c_str(), nullptr, MAT_FT_MAT5);
    put(mat, "F", MAT_C_SINGLE, MAT_T_SINGLE, n, 3, single.data(), MAT_COMPRESSION_ZLIB);
    put(mat, "t", MAT_C_DOUBLE, MAT_T_DOUBLE, n, 1, t.data(), MAT_COMPRESSION_ZLIB);
    Mat_Close(mat);
  }
  {
    mat_t* mat = Mat_CreateVer((dir + "/v4_matrix.mat").c_str(), nullptr, MAT_FT_MAT4);
    put(mat, "force", MAT_C_DOUBLE, MAT_T_DOUBLE, n, 3, m.data());
    put(mat, "fs", MAT_C_DOUBLE, MAT_T_DOUBLE, 1, 1, &rate);
    Mat_Close(mat);
  }
  {
    mat_t* mat = Mat_CreateVer((dir + "/v73_vectors.mat").c_str(), nullptr, MAT_FT_MAT73);
    put(mat, "fx", MAT_C_DOUBLE, MAT_T_DOUBLE, n, 1, fx.data());
    put(mat, "fy", MAT_C_DOUBLE, MAT_T_DOUBLE, n, 1, fy.data());
    put(mat, "fz", MAT_C_DOUBLE, MAT_T_DOUBLE, n, 1, fz.data());
    put(mat, "time", MAT_C_DOUBLE, MAT_T_DOUBLE, n, 1, t.data());
    Mat_Close(mat);
  }
  {
    mat_t* mat = Mat_CreateVer((dir + "/v5_int16_rows.mat").c_str(), nullptr, MAT_FT_MAT5);
    put(mat, "data", MAT_C_INT16, MAT_T_INT16, 3, n, counts.data());
    put(mat, "sample_rate_hz", MAT_C_DOUBLE, MAT_T_DOUBLE, 1, 1, &rate);
    Mat_Close(mat);
  }
  {
    mat_t* mat = Mat_CreateVer((dir + "/v5_struct.mat").c_str(), nullptr, MAT_FT_MAT5);
    const char* fields[] = {"Fx", "Fy", "Fz", nullptr};
    std::size_t one[2] = {1, 1};
    std::size_t dims[2] = {n, 1};
    matvar_t* s = Mat_VarCreateStruct2("run", 2, one, fields);
    Mat_VarSetStructFieldByName(
        s, "Fx", 0, Mat_VarCreate(nullptr, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, fx.data(), 0));
    Mat_VarSetStructFieldByName(
        s, "Fy", 0, Mat_VarCreate(nullptr, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, fy.data(), 0));
    Mat_VarSetStructFieldByName(
        s, "Fz", 0, Mat_VarCreate(nullptr, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, fz.data(), 0));
    Mat_VarWrite(mat, s, MAT_COMPRESSION_NONE);
    Mat_VarFree(s);
    put(mat, "fx", MAT_C_DOUBLE, MAT_T_DOUBLE, n, 1, fx.data());  // decoys by the usual names
    put(mat, "fy", MAT_C_DOUBLE, MAT_T_DOUBLE, n - 1, 1, fy.data());
    put(mat, "fz", MAT_C_DOUBLE, MAT_T_DOUBLE, n, 1, fz.data());
    Mat_Close(mat);
  }
  return 0;
}
