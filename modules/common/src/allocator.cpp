#include <paco/common/allocator.h>

#include <cstdlib>  // defines __GLIBC__ on glibc

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace paco {

bool keepFreedMemoryForReuse() {
#if defined(__GLIBC__)
  // Blocks up to 32 MiB (glibc's largest allowed threshold on 64-bit systems) come from the heap,
  // whose freed memory is reused; the heap is trimmed only when 1 GiB lies free at its top.
  const bool mapped = mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024) == 1;
  const bool trimmed = mallopt(M_TRIM_THRESHOLD, 1024 * 1024 * 1024) == 1;
  return mapped && trimmed;
#else
  return false;
#endif
}

}  // namespace paco
