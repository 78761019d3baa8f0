// SPDX-License-Identifier: MIT
#include "apps/allocator_tuning.h"

#include <malloc.h>

namespace nfield::apps {

void keep_freed_blocks_in_the_heap() {
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 128 << 20);
}

}  // namespace nfield::apps
