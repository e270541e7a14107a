#pragma once
// How a regbench process hands memory back to the system.

namespace regbench {

/// Makes the process keep the memory it frees for its next allocations (glibc: no mmap for
/// large blocks, no trimming of the heap). A network forward or training step allocates and
/// frees the same large tensors every call; by default glibc serves each block above its mmap
/// threshold with a fresh mmap and unmaps it on free, so every 4 KiB page of it is a page fault
/// with the kernel zeroing it, every call (training: 210,000-590,000 faults a step, 60-80% of
/// its CPU time; RIENet's inference forward: about two thirds of its CPU time; see
/// docs/performance.md). The cost: the process's heap stays at its peak. Called by `regbench`'s
/// main, the benchmarks' main and networks::Train(); a library (the Python module) leaves the host
/// process's allocator alone. No effect without glibc. Idempotent.
void RetainFreedMemory();

}  // namespace regbench
