#include <paco/common/error.h>
#include <paco/io/cloud_io.h>
#include <paco/io/npy_io.h>

#include <gtest/gtest.h>

#include "test_support.h"

#include <cmath>
#include <cstdint>

namespace {

using paco::IoError;
using paco::test::TempDir;
using paco::test::readBytes;
using paco::test::writeBytes;

/// A .npy file as NumPy writes it, with the given header dict and raw data.
std::string npyBytes(const std::string& dict, const std::string& data, int major = 1) {
  std::string header = dict;
  const std::size_t prefix = major == 1 ? 10 : 12;
  while ((prefix + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::string out = "\x93NUMPY";
  out += static_cast<char>(major);
  out += '\0';
  if (major == 1) {
    const auto len = static_cast<std::uint16_t>(header.size());
    out.append(reinterpret_cast<const char*>(&len), 2);
  } else {
    const auto len = static_cast<std::uint32_t>(header.size());
    out.append(reinterpret_cast<const char*>(&len), 4);
  }
  return out + header + data;
}

template <typename T>
std::string raw(std::initializer_list<T> values) {
  std::string out;
  for (T v : values) out.append(reinterpret_cast<const char*>(&v), sizeof(T));
  return out;
}

void expectNpyError(const std::string& path, const std::string& problem) {
  try {
    paco::io::loadNpy(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const IoError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(problem), std::string::npos) << "expected '" << problem << "' in: " << msg;
  }
}

TEST(NpyIo, RoundTripFloat32AndFloat64) {
  TempDir dir;
  paco::io::NpyArray a;
  a.rows = 3;
  a.cols = 7;
  for (int i = 0; i < 21; ++i) a.data.push_back(0.1 * i - 1.0);
  paco::io::saveNpy(dir.file("d.npy"), a, true);
  const auto d = paco::io::loadNpy(dir.file("d.npy"));
  EXPECT_EQ(d.rows, 3u);
  EXPECT_EQ(d.cols, 7u);
  EXPECT_EQ(d.data, a.data);
  paco::io::saveNpy(dir.file("f.npy"), a, false);
  const auto f = paco::io::loadNpy(dir.file("f.npy"));
  for (std::size_t i = 0; i < a.data.size(); ++i) EXPECT_EQ(f.data[i], static_cast<double>(static_cast<float>(a.data[i])));
  // The header is padded to 64 bytes, as NumPy's own writer does.
  EXPECT_EQ((readBytes(dir.file("f.npy")).size() - 21 * 4) % 64, 0u);
}

TEST(NpyIo, ReadsVersion2HeadersAnyKeyOrderAndFortranOrder) {
  TempDir dir;
  writeBytes(dir.file("v2.npy"), npyBytes("{'shape': (2, 3), 'fortran_order': False, 'descr': '<f4'}",
                                          raw<float>({1, 2, 3, 4, 5, 6}), 2));
  auto a = paco::io::loadNpy(dir.file("v2.npy"));
  EXPECT_EQ(a.rows, 2u);
  EXPECT_EQ(a.cols, 3u);
  EXPECT_EQ(a.at(1, 0), 4.0);
  // Column-major storage: the same matrix stored column by column.
  writeBytes(dir.file("f.npy"), npyBytes("{'descr': '<f8', 'fortran_order': True, 'shape': (2, 3), }",
                                         raw<double>({1, 4, 2, 5, 3, 6})));
  a = paco::io::loadNpy(dir.file("f.npy"));
  EXPECT_EQ(a.data, (std::vector<double>{1, 2, 3, 4, 5, 6}));
  // 1-D arrays are one column.
  writeBytes(dir.file("one.npy"), npyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (4,), }",
                                           raw<float>({1, 2, 3, 4})));
  a = paco::io::loadNpy(dir.file("one.npy"));
  EXPECT_EQ(a.rows, 4u);
  EXPECT_EQ(a.cols, 1u);
}

TEST(NpyIo, AuthorsSevenColumnLayoutLoadsAsLabelledCloud) {
  TempDir dir;
  writeBytes(dir.file("s.npy"), npyBytes("{'descr': '<f8', 'fortran_order': False, 'shape': (2, 7), }",
                                         raw<double>({0.5, 1, 2, 0, 0, 1, 3, -1, -2, -3, 1, 0, 0, -1})));
  const auto c = paco::io::loadCloud(dir.file("s.npy"));
  ASSERT_EQ(c.points.size(), 2u);
  EXPECT_TRUE(c.has_normals);
  EXPECT_EQ(c.labels, (std::vector<int>{3, -1}));
  EXPECT_EQ(c.points[0].x, 0.5f);
  EXPECT_EQ(c.points[1].normal_x, 1.0f);
  writeBytes(dir.file("six.npy"), npyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 6), }",
                                           raw<float>({1, 2, 3, 0, 1, 0})));
  const auto six = paco::io::loadCloud(dir.file("six.npy"));
  EXPECT_TRUE(six.has_normals);
  EXPECT_FALSE(six.hasLabels());
}

TEST(NpyIoErrors, MissingEmptyTruncatedMalformedAndNonFinite) {
  TempDir dir;
  expectNpyError(dir.file("absent.npy"), "file not found");
  writeBytes(dir.file("empty.npy"), "");
  expectNpyError(dir.file("empty.npy"), "empty");
  writeBytes(dir.file("magic.npy"), "PK\x03\x04 this is a zip (.npz)");
  expectNpyError(dir.file("magic.npy"), "not a .npy file");
  writeBytes(dir.file("short.npy"), "\x93NUM");
  expectNpyError(dir.file("short.npy"), "truncated: the .npy header is cut off");
  writeBytes(dir.file("cut.npy"), npyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (2048, 7), }",
                                           std::string(1000 * 7 * 4, '\0')));
  expectNpyError(dir.file("cut.npy"), "truncated: header says shape (2048, 7), i.e. 14336 values, data holds 7000");
  std::string header_cut = npyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 3), }", "");
  header_cut.resize(30);
  writeBytes(dir.file("hcut.npy"), header_cut);
  expectNpyError(dir.file("hcut.npy"), "truncated: the .npy header says");
  writeBytes(dir.file("int.npy"), npyBytes("{'descr': '<i8', 'fortran_order': False, 'shape': (1, 3), }", raw<std::int64_t>({1, 2, 3})));
  expectNpyError(dir.file("int.npy"), "unsupported .npy dtype '<i8'");
  writeBytes(dir.file("dict.npy"), npyBytes("{'descr': '<f4', 'fortran_order': Maybe, 'shape': (1, 3), }", raw<float>({1, 2, 3})));
  expectNpyError(dir.file("dict.npy"), "malformed .npy header");
  writeBytes(dir.file("noshape.npy"), npyBytes("{'descr': '<f4', 'fortran_order': False}", raw<float>({1, 2, 3})));
  expectNpyError(dir.file("noshape.npy"), "no 'shape' entry");
  writeBytes(dir.file("3d.npy"), npyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 1, 3), }", raw<float>({1, 2, 3})));
  expectNpyError(dir.file("3d.npy"), "3 dimensions");
  writeBytes(dir.file("v9.npy"), std::string("\x93NUMPY\x09\x00\x10\x00", 10) + std::string(16, ' '));
  expectNpyError(dir.file("v9.npy"), "unsupported .npy format version 9");
  // As a cloud: wrong column count, non-integral plane ids, NaN coordinates.
  writeBytes(dir.file("cols.npy"), npyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 4), }", raw<float>({1, 2, 3, 4})));
  EXPECT_THROW(paco::io::loadCloud(dir.file("cols.npy")), IoError);
  writeBytes(dir.file("id.npy"), npyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (1, 7), }",
                                          raw<float>({1, 2, 3, 0, 0, 1, 0.5f})));
  EXPECT_THROW(paco::io::loadCloud(dir.file("id.npy")), IoError);
  writeBytes(dir.file("nan.npy"), npyBytes("{'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }",
                                           raw<float>({1, 2, 3, 4, NAN, 6})));
  try {
    paco::io::loadCloud(dir.file("nan.npy"));
    ADD_FAILURE();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("non-finite"), std::string::npos) << e.what();
  }
  // Unwritable path and inconsistent arrays.
  paco::io::NpyArray a;
  a.rows = 1;
  a.cols = 3;
  a.data = {1, 2, 3};
  EXPECT_THROW(paco::io::saveNpy(dir.file("no/dir/a.npy"), a), IoError);
  a.data.pop_back();
  EXPECT_THROW(paco::io::saveNpy(dir.file("a.npy"), a), IoError);
}

}  // namespace
