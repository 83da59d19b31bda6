#include <paco/common/allocator.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

// A sanitizer's allocator (the build's PACO_SANITIZE) replaces glibc's, and with it what mallinfo2
// reports.
#if defined(__GLIBC__) && !defined(PACO_SANITIZER_ALLOCATOR)
#define PACO_TEST_GLIBC_MALLOC 1
#else
#define PACO_TEST_GLIBC_MALLOC 0
#endif

namespace {

// After the call, a block of 8 MB (far above glibc's default mapping threshold of 128 KB) comes
// from the heap rather than a mapping of its own, and stays with the heap when freed, ready for
// the next tensor.
TEST(Allocator, FreedMemoryIsKeptForReuse) {
#if PACO_TEST_GLIBC_MALLOC
  ASSERT_TRUE(paco::keepFreedMemoryForReuse());
  const std::size_t size = 8u << 20;
  const std::size_t mapped_before = mallinfo2().hblkhd;
  auto* block = static_cast<volatile char*>(std::malloc(size));
  ASSERT_NE(block, nullptr);
  for (std::size_t i = 0; i < size; i += 4096) block[i] = 1;  // touch it, so it cannot be elided
  EXPECT_EQ(mallinfo2().hblkhd, mapped_before);  // not a mapping of its own
  std::free(const_cast<char*>(block));
  EXPECT_GE(mallinfo2().fordblks, size);  // free in the heap, not handed back
#else
  GTEST_SKIP() << "not glibc's allocator (another C library, or a sanitizer's)";
#endif
}

}  // namespace
