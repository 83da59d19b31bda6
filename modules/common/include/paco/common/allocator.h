#pragma once
// Usage (once, at the start of a program that runs the network or trains it):
//   paco::keepFreedMemoryForReuse();

namespace paco {

/// Makes the C library's malloc keep freed memory for reuse instead of handing it back to the
/// system. LibTorch allocates and frees tensors of megabytes in every layer; by default glibc maps
/// such blocks afresh and unmaps them, or trims the heap, when they are freed, so every layer
/// pays for its memory again in page faults (and, with two threads, in flushes of the other
/// core's address cache). With this setting, on the 2 cores of the fifty-fifth session's machine,
/// the completion of a scan (four turns of the network) takes 20-30 % less time, and a training
/// step at batch 16 20-40 % less, with the same peak memory (doc/benchmarks.md). Freed memory
/// stays with the process until it exits. Every paco_* tool calls it at start; call it in your
/// own program for the same speed. Returns false where the C library has no such setting (not
/// glibc), where nothing changes.
bool keepFreedMemoryForReuse();

}  // namespace paco
