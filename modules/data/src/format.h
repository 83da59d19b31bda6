#pragma once
// Internal: the part-file layout of doc/dataset.md ("PACOPART" v1), shared by writer and reader.
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the dataset format is little-endian");

namespace paco::data::detail {

constexpr char kPartMagic[8] = {'P', 'A', 'C', 'O', 'P', 'A', 'R', 'T'};
constexpr std::uint32_t kPartVersion = 1;
constexpr std::size_t kHeaderBytes = 136;        // magic .. augmentation matrix
constexpr std::size_t kPlaneBytes = 5 * 8;       // f64 nx ny nz d area
constexpr std::size_t kPointBytes = 7 * 4;       // f32 x y z nx ny nz plane_id
constexpr std::size_t kSampleHeaderBytes = 24;   // u32 level, u32 view, f32 viewpoint[3], f32 missing

struct PartHeader {
  std::uint32_t version = kPartVersion;
  std::uint32_t num_planes = 0, num_gt = 0, num_samples = 0, input_points = 0, flags = 0;
  double center[3] = {0, 0, 0};
  double scale = 1.0;
  double augmentation[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};

  std::size_t gtOffset() const { return kHeaderBytes + kPlaneBytes * num_planes; }
  std::size_t sampleBytes() const { return kSampleHeaderBytes + kPointBytes * input_points; }
  std::size_t sampleOffset(std::size_t slot) const { return gtOffset() + kPointBytes * num_gt + slot * sampleBytes(); }
  std::size_t fileBytes() const { return sampleOffset(num_samples); }
};

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

template <typename T>
T get(const char* data, std::size_t& offset) {
  T value;
  std::memcpy(&value, data + offset, sizeof(T));
  offset += sizeof(T);
  return value;
}

}  // namespace paco::data::detail
