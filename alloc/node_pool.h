// NodePool: fixed-size node allocation owned per worker slot.
//
// Each worker slot owns a heap of 64 KiB pages carved from 4 MiB slabs (madvised for huge
// pages). A page keeps its own free set, a bitmap, and hands out its lowest free node, so after
// a whole generation of nodes dies in random order a heap still allocates page by page in
// address order (mimalloc's page-sharded free lists, jemalloc's slab bitmaps; one global LIFO
// list measured ~170 ns per allocation after random frees on this machine kind).
//
// Allocation and a free by the owning slot touch no atomics. A node freed by another slot goes
// into that slot's outgoing batch for the owner (an array of kRemoteBatch node pointers), and a
// full batch, or any batch at Flush(slot), is pushed onto the owner's remote list with one
// atomic exchange; the owner drains its remote lists when its current page runs out (mimalloc's
// `_local` / `_mt` split). Batches spare an atomic per free, and the owner's drain reads an
// array instead of chasing a `next` link through each node, a cache miss on a line the freeing
// core last wrote. A node freed by a thread outside the engine (kForeignSlot), or when no batch
// can be allocated, is pushed alone. The remote lists are multi-producer, single-consumer and
// consumed whole with one exchange, so there is no ABA (unlike a Treiber stack popped one node at
// a time: immer issue #182).
//
// Invariants:
//   1. A slot's heap is touched only by the thread currently holding that slot (the WorkerPool
//      guarantees one thread per slot at a time); the remote list is the only shared field.
//   2. Every page header sits at the start of its 64 KiB-aligned page, so the owner of any node
//      is found by masking its address.
//   3. live = allocations - local frees - drained remote frees, per slot; nodes on a remote list
//      are counted in the owner's remote_pending until drained, nodes in an outgoing batch in
//      the freeing slot's outgoing count until pushed.
//
// With GROVE_NODE_POOL off, Allocate/Free are plain aligned new/delete with the same counters
// (sanitizer and valgrind builds: pooled memory would hide use-after-free).
//
// Allocation never throws: when the system refuses memory (or an injected failure fires, see
// FailAllocationsAfter) Allocate() returns nullptr and the caller reports ResourceExhausted.
//
// Thread safety: Allocate(slot), Free(p, slot) and Flush(slot) may run concurrently for
// distinct slots; Free(p, kForeignSlot) from any thread; Stats() from any thread at any time.
#ifndef GROVE_ALLOC_NODE_POOL_H_
#define GROVE_ALLOC_NODE_POOL_H_

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace grove {

// The slot of a thread that is not one of an engine's workers.
inline constexpr int kForeignSlot = -1;

struct PoolStats {
  int64_t node_bytes = 0;  // size of one node
  int64_t live_nodes = 0;  // allocated and not yet freed
  // The highest live_nodes seen: the count at each Stats() call, or the sum of each slot's own
  // highest count (sampled at its page refills) when that is higher. With one slot it is the
  // peak sampled at refills; with several it can exceed the true peak (the slots' highs need
  // not coincide), and is close to it when the slots grow and shrink together.
  int64_t peak_live_nodes = 0;
  int64_t reserved_bytes = 0;  // memory obtained from the system (slabs)
  int64_t live_bytes() const { return live_nodes * node_bytes; }
  int64_t peak_live_bytes() const { return peak_live_nodes * node_bytes; }
};

// Fault injection for tests: after `allocations` more successful node allocations, in any
// pool of the process, every further one fails (returns nullptr) until the countdown is reset
// with a negative value (the default: never fail). A test-only switch: the one process-wide
// state of the library, checked with a relaxed load that is almost always -1.
void FailAllocationsAfter(int64_t allocations);

class NodePool {
 public:
  // REQUIRES: 8 <= node_bytes <= 16 KiB, slots >= 1.
  NodePool(size_t node_bytes, int slots);
  ~NodePool();  // returns all slabs; nodes still live become invalid
  NodePool(const NodePool&) = delete;
  NodePool& operator=(const NodePool&) = delete;

  // Returns uninitialised storage of node_bytes(), 16-byte aligned (64-byte aligned when
  // node_bytes() is a multiple of 64: each such node has its cache lines to itself), or nullptr
  // when no memory can be had. REQUIRES: 0 <= slot < slots().
  void* Allocate(int slot);
  // REQUIRES: p came from Allocate on this pool; slot is the caller's slot or kForeignSlot.
  void Free(void* p, int slot);
  // Hands the nodes `slot` freed for other slots, still in its outgoing batches, to their
  // owners (a free by another slot reaches the owner in batches of kRemoteBatch, or here).
  // Callers flush at the end of a phase of frees; memory is never lost without it, only
  // reused later.
  void Flush(int slot);

  // Nodes per batch of remote frees.
  static constexpr int kRemoteBatch = 62;

  PoolStats Stats() const;
  size_t node_bytes() const { return node_bytes_; }
  int slots() const { return static_cast<int>(heaps_.size()); }
  static constexpr bool kPooling =
#ifdef GROVE_NODE_POOL
      true;
#else
      false;
#endif

 private:
  struct Heap;
  struct Page;
  struct FreeNode {
    FreeNode* next;
  };
  // 512 bytes: a batch of nodes freed by one slot for another's heap.
  struct RemoteBatch {
    RemoteBatch* next;
    int count;
    void* nodes[kRemoteBatch];
  };

  Page* Refill(Heap* heap);
  void DrainRemote(Heap* heap);
  void PushNode(Heap* owner, void* p);
  void PushBatch(Heap* owner, RemoteBatch* batch);
  void LocalFree(Heap* heap, Page* page, void* node);
  void NotePeak() const;

  size_t node_bytes_;
  uint32_t first_node_offset_;  // bytes reserved for the page header
  uint32_t nodes_per_page_;
  std::vector<std::unique_ptr<Heap>> heaps_;
  mutable std::atomic<int64_t> peak_live_{0};
  std::atomic<int64_t> reserved_bytes_{0};
};

}  // namespace grove

#endif  // GROVE_ALLOC_NODE_POOL_H_
