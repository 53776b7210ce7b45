/* A prefix sum in place over n entries in three launches of independent work items (no work-group size
 * assumed; a GPU runs PC_SCAN_BLOCKS chunks at once instead of one thread over every entry): each block's
 * running sums over its chunk (scan_block), the blocks' offsets by one work item (scan_offsets: kept after
 * the entries at a[n + 1 + block], the total at a[n]), each chunk's offset added (scan_add). The order of the
 * additions is fixed by n alone: integer and float sums alike are the same bits on every device, however
 * the launches run. vcm.cl's grid (uint) and mlt.cl's bootstrap (float) take it; the arrays hold n + 1 +
 * PC_SCAN_BLOCKS entries. */
#ifndef PATHCL_SCAN_CL
#define PATHCL_SCAN_CL

static inline uint scan_chunk(uint n) { return (n + PC_SCAN_BLOCKS - 1u) / PC_SCAN_BLOCKS; }

#define PC_SCAN_FUNCTIONS(T)                                                            \
  static inline void scan_block_##T(__global T* a, uint n, uint block) {               \
    uint chunk = scan_chunk(n);                                                         \
    T sum = (T)(0);                                                                     \
    for (uint i = block * chunk; i < min(n, (block + 1u) * chunk); ++i) {               \
      sum += a[i];                                                                      \
      a[i] = sum;                                                                       \
    }                                                                                   \
    a[n + 1u + block] = sum;                                                            \
  }                                                                                     \
  static inline void scan_offsets_##T(__global T* a, uint n) {                         \
    T total = (T)(0);                                                                   \
    for (uint block = 0; block < PC_SCAN_BLOCKS; ++block) {                            \
      T sum = a[n + 1u + block];                                                        \
      a[n + 1u + block] = total;                                                        \
      total += sum;                                                                     \
    }                                                                                   \
    a[n] = total;                                                                       \
  }                                                                                     \
  static inline void scan_add_##T(__global T* a, uint n, uint block) {                 \
    uint chunk = scan_chunk(n);                                                         \
    T offset = a[n + 1u + block];                                                       \
    for (uint i = block * chunk; i < min(n, (block + 1u) * chunk); ++i) a[i] += offset; \
  }
PC_SCAN_FUNCTIONS(uint)
PC_SCAN_FUNCTIONS(float)
#undef PC_SCAN_FUNCTIONS

#endif
