#pragma once
// An index of a std::map<int, V>'s entries by id, for the lookups a cycle makes per vehicle: at
// 10,000 vehicles the map's nodes lie scattered over the heap and a find is a cache miss a level.
// Ids from 0 below kDenseIds are kept in a vector of pointers to the map's nodes (a node never
// moves); any other id is looked up in the map. The owner adds each entry it inserts and rebuilds
// the index when it replaces the map, and is not copyable (the pointers are into its own map).
#include <cstddef>
#include <map>
#include <utility>
#include <vector>

namespace sage::server {

template <class V>
class IdIndex {
 public:
  static constexpr int kDenseIds = 1 << 20;

  void Add(int id, V& entry) {
    if (id < 0 || id >= kDenseIds) return;
    const auto at = static_cast<std::size_t>(id);
    if (at >= by_id_.size()) by_id_.resize(at + 1, nullptr);
    by_id_[at] = &entry;
  }
  void Rebuild(std::map<int, V>& map) {
    by_id_.clear();
    for (auto& [id, entry] : map) Add(id, entry);
  }
  V* Find(std::map<int, V>& map, int id) const { return const_cast<V*>(Find(std::as_const(map), id)); }
  const V* Find(const std::map<int, V>& map, int id) const {
    if (id >= 0 && id < kDenseIds) {
      return static_cast<std::size_t>(id) < by_id_.size() ? by_id_[static_cast<std::size_t>(id)] : nullptr;
    }
    const auto it = map.find(id);
    return it == map.end() ? nullptr : &it->second;
  }

 private:
  std::vector<V*> by_id_;
};

}  // namespace sage::server
