// The allocator settings of a process that moves frames: call first thing in main().
#pragma once

#include <malloc.h>

namespace brdfa {

// Frames are buffers of a megabyte or more, made and freed several times a second per session
// (read back, handed between threads, encoded). Above glibc's default mmap threshold each one
// would be mapped fresh, faulted in page by page and unmapped again; with the threshold and the
// trim threshold raised they are reused from the heap.
inline void keepFrameBuffersInHeap() {
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 128 << 20);
}

}  // namespace brdfa
