// LZF stream format: a control byte c < 32 starts a run of c + 1 literal bytes; otherwise
// len = c >> 5 (7 means "add the next byte"), and the back-reference copies len + 2 bytes from
// ((c & 31) << 8 | next byte) + 1 bytes back.
#include "lzf.h"

#include <cstdint>
#include <algorithm>
#include <cstring>
#include <vector>

namespace paco::io::detail {

namespace {
constexpr std::size_t kMaxLiteral = 32;
constexpr std::size_t kMaxOffset = 8192;
constexpr std::size_t kMaxMatch = 264;  // 7 + 255 + 2
constexpr int kHashBits = 14;

std::uint32_t hash3(const unsigned char* p) {
  const std::uint32_t v = (std::uint32_t{p[0]} << 16) | (std::uint32_t{p[1]} << 8) | p[2];
  return (v * 2654435761u) >> (32 - kHashBits);
}
}  // namespace

std::string lzfCompress(std::string_view in) {
  const auto* data = reinterpret_cast<const unsigned char*>(in.data());
  const std::size_t n = in.size();
  std::string out;
  out.reserve(n + n / 32 + 16);
  std::vector<std::size_t> table(std::size_t{1} << kHashBits, SIZE_MAX);
  std::size_t literal_start = 0;  // first byte not yet emitted
  const auto flushLiterals = [&](std::size_t end) {
    while (literal_start < end) {
      const std::size_t run = std::min(kMaxLiteral, end - literal_start);
      out += static_cast<char>(run - 1);
      out.append(in.data() + literal_start, run);
      literal_start += run;
    }
  };
  std::size_t i = 0;
  while (i + 2 < n) {
    const std::uint32_t h = hash3(data + i);
    const std::size_t candidate = table[h];
    table[h] = i;
    if (candidate != SIZE_MAX && i - candidate <= kMaxOffset && std::memcmp(data + candidate, data + i, 3) == 0) {
      std::size_t len = 3;
      while (len < kMaxMatch && i + len < n && data[candidate + len] == data[i + len]) ++len;
      flushLiterals(i);
      const std::size_t offset = i - candidate - 1;
      const std::size_t code = len - 2;
      if (code < 7) {
        out += static_cast<char>((code << 5) | (offset >> 8));
      } else {
        out += static_cast<char>((7 << 5) | (offset >> 8));
        out += static_cast<char>(code - 7);
      }
      out += static_cast<char>(offset & 0xff);
      for (std::size_t k = 1; k < len && i + k + 2 < n; ++k) table[hash3(data + i + k)] = i + k;
      i += len;
      literal_start = i;
    } else {
      ++i;
    }
  }
  flushLiterals(n);
  return out;
}

bool lzfDecompress(std::string_view in, std::size_t expected_size, std::string& out) {
  out.clear();
  out.reserve(expected_size);
  const auto* p = reinterpret_cast<const unsigned char*>(in.data());
  const unsigned char* end = p + in.size();
  while (p < end) {
    const unsigned int ctrl = *p++;
    if (ctrl < 32) {
      const std::size_t run = ctrl + 1;
      if (static_cast<std::size_t>(end - p) < run || out.size() + run > expected_size) return false;
      out.append(reinterpret_cast<const char*>(p), run);
      p += run;
      continue;
    }
    std::size_t len = ctrl >> 5;
    if (len == 7) {
      if (p >= end) return false;
      len += *p++;
    }
    len += 2;
    if (p >= end) return false;
    const std::size_t offset = ((ctrl & 31u) << 8 | *p++) + 1;
    if (offset > out.size() || out.size() + len > expected_size) return false;
    const std::size_t from = out.size() - offset;
    for (std::size_t k = 0; k < len; ++k) out += out[from + k];  // may overlap itself
  }
  return out.size() == expected_size;
}

}  // namespace paco::io::detail
