#pragma once
// FNV-1a (64 bits): a hash of bytes that is the same on every machine, compiler and run, for the
// keys paco stores or derives from names: the dataset split of a part, a network's fingerprint in
// an extent head, the samples a feature cache was made for.
//   std::uint64_t key = paco::fnv1a("part-0001");
//   key = paco::fnv1a("more", key);   // continues the same hash
#include <cstdint>
#include <string_view>

namespace paco {

constexpr std::uint64_t kFnv1aOffsetBasis = 14695981039346656037ull;

/// The FNV-1a hash of `bytes`, continuing `hash` (the offset basis starts a new one).
inline std::uint64_t fnv1a(std::string_view bytes, std::uint64_t hash = kFnv1aOffsetBasis) {
  for (unsigned char c : bytes) hash = (hash ^ c) * 1099511628211ull;
  return hash;
}

}  // namespace paco
