/*
 * Splitting the element-wise work around the matrix products over the
 * cores.  The products themselves run on the BLAS's threads; everything
 * between them (encodings, bias and activation passes, sampling,
 * compositing, the optimiser) would otherwise run on one core while the
 * others wait for the next product.
 *
 * One process-wide pool of sleeping workers serves every handle.  A call
 * made while the pool is busy (another thread's call, or a call from inside
 * a range function) runs its ranges on the calling thread instead, so
 * callers never wait for each other and nesting cannot deadlock.
 *
 * Results must not depend on the split: range functions write disjoint
 * outputs, and reductions go through nerf__parallel_blocks(), whose blocks
 * are fixed by the caller and combined in order, so sums are the same for
 * any thread count.
 */
#ifndef NERF_COMMON_PARALLEL_H
#define NERF_COMMON_PARALLEL_H

#include <stddef.h>

/* Work on items [begin, end). */
typedef void (*nerf__range_fn)(void *ctx, size_t begin, size_t end);

/* Floating-point operations of a vectorised matrix kernel that take about
 * as long as one simple operation (8-wide fused multiply-adds). */
#define NERF__FLOPS_PER_OP 32

/*
 * Call fn over [0, n) in contiguous ranges, on up to every core.  `cost` is
 * the rough work per item in simple operations: scalar instructions, about
 * four to a nanosecond.  Vectorised multiply-adds count NERF__FLOPS_PER_OP
 * to the operation.  Small jobs (n * cost below a threshold where waking a
 * worker costs more than it saves) run on the calling thread.  Returns when
 * every range is done.
 */
void nerf__parallel_for(size_t n, size_t cost, nerf__range_fn fn, void *ctx);

/*
 * Call fn(ctx, block) for block in [0, n_blocks), spread over the cores;
 * for reductions whose partial results are kept per block.
 */
typedef void (*nerf__block_fn)(void *ctx, size_t block);
void nerf__parallel_blocks(size_t n_blocks, size_t cost_per_block,
                           nerf__block_fn fn, void *ctx);

/* Threads the pool may use, the caller included (at least 1). */
unsigned nerf__parallel_threads(void);

/*
 * For threads that are themselves one of a set covering every core (the
 * renderer's workers): with `on`, this thread's calls run their ranges
 * itself instead of handing some to the pool, whose workers would only
 * compete with the set's other threads for the cores.
 */
void nerf__parallel_set_inline(int on);

#endif
