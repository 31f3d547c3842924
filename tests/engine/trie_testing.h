// Update() for tests and benchmarks that never run out of memory: returns the new root.
#ifndef GROVE_TESTS_ENGINE_TRIE_TESTING_H_
#define GROVE_TESTS_ENGINE_TRIE_TESTING_H_

#include <cstdint>
#include <utility>

#include "alloc/check.h"

namespace grove {

template <typename Trie, typename F>
typename Trie::Root TrieUpdated(Trie& trie, typename Trie::Root root, uint64_t key, int slot,
                                F&& f) {
  GROVE_CHECK(trie.Update(&root, key, slot, std::forward<F>(f)));
  return root;
}

}  // namespace grove

#endif  // GROVE_TESTS_ENGINE_TRIE_TESTING_H_
