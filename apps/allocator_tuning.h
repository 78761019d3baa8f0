// SPDX-License-Identifier: MIT
//
// The allocator setting the nfield program asks for at start-up. The library never changes
// process-wide state by itself; a program that embeds it decides whether to do the same.
//
// Eigen allocates the packing buffers of every matrix product (0.1–2 MB in a training step)
// on the heap, and glibc's defaults hand such blocks back to the kernel when they are freed
// (mmap above 128 KiB, heap trimming above 128 KiB), so every product page-faults its
// buffers anew: a training process ran markedly slower per step (docs/experiments.md) until
// something large had moved glibc's adaptive thresholds. Raising the
// mmap threshold to 32 MiB and the trim threshold to 128 MiB keeps freed blocks in the heap,
// at the cost of at most the trim threshold in retained memory.
#pragma once

namespace nfield::apps {

// Raises glibc's mmap and trim thresholds as described above. Call once, before training.
void keep_freed_blocks_in_the_heap();

}  // namespace nfield::apps
