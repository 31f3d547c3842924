// HexTable: a hash table from H-tree keys to a value per hexagon, open addressing with linear
// probing, power-of-two capacity, at most half full. The naive map's per-particle tables and the
// prior map's one shared table.
//
// Thread safety: const methods may run concurrently; nothing else may run beside them.
#ifndef GROVE_ENGINE_FOOTSLAM_HEX_TABLE_H_
#define GROVE_ENGINE_FOOTSLAM_HEX_TABLE_H_

#include <cstddef>
#include <cstdint>
#include <vector>

namespace grove::footslam {

template <typename Value>
class HexTable {
 public:
  // The value under `key`, value-initialised if it was not there. May grow the table (a
  // std::bad_alloc then leaves it unchanged).
  Value& FindOrInsert(uint64_t key) {
    if ((size_ + 1) * 2 > slots_.size()) Grow();
    const size_t mask = slots_.size() - 1;
    for (size_t i = Hash(key) & mask;; i = (i + 1) & mask) {
      if (slots_[i].tag == 0) {
        slots_[i].tag = key + 1;
        slots_[i].value = Value{};
        ++size_;
        return slots_[i].value;
      }
      if (slots_[i].tag == key + 1) return slots_[i].value;
    }
  }
  // Adds a hexagon that is not there yet; false when `key` is present already.
  bool Insert(uint64_t key, const Value& value) {
    const size_t before = size_;
    Value& slot = FindOrInsert(key);
    if (size_ == before) return false;
    slot = value;
    return true;
  }
  // The value under `key`, or nullptr.
  const Value* Find(uint64_t key) const {
    if (size_ == 0) return nullptr;
    const size_t mask = slots_.size() - 1;
    for (size_t i = Hash(key) & mask;; i = (i + 1) & mask) {
      if (slots_[i].tag == key + 1) return &slots_[i].value;
      if (slots_[i].tag == 0) return nullptr;
    }
  }
  // f(key, const Value&) for every hexagon, in slot order.
  template <typename F>
  void ForEach(F&& f) const {
    for (const Slot& s : slots_) {
      if (s.tag != 0) f(s.tag - 1, s.value);
    }
  }
  size_t size() const { return size_; }
  size_t bytes() const { return slots_.size() * sizeof(Slot); }

 private:
  struct Slot {
    uint64_t tag;  // key + 1; 0 marks an empty slot
    Value value;
  };
  static size_t Hash(uint64_t key) { return (key * 0x9E3779B97F4A7C15ull) >> 20; }
  void Grow() {
    std::vector<Slot> old(slots_.empty() ? 16 : slots_.size() * 2, Slot{0, Value{}});
    old.swap(slots_);  // allocated first: a std::bad_alloc leaves the table as it was
    size_ = 0;
    for (const Slot& s : old) {
      if (s.tag != 0) FindOrInsert(s.tag - 1) = s.value;
    }
  }

  std::vector<Slot> slots_;
  size_t size_ = 0;
};

}  // namespace grove::footslam

#endif  // GROVE_ENGINE_FOOTSLAM_HEX_TABLE_H_
