#include "core/memory_policy.hpp"

#include <cstddef>  // defines __GLIBC__ on glibc systems

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace regbench {

void RetainFreedMemory() {
#if defined(__GLIBC__)
    mallopt(M_MMAP_MAX, 0);         // large blocks from the heap, where freed ones are reused
    mallopt(M_TRIM_THRESHOLD, -1);  // and the heap's top is never given back (mallopt(3))
#endif
}

}  // namespace regbench
