#pragma once
// The heap memory a container's elements take, for a session's memory budget
// (session::PipelineOptions::max_held_bytes, docs/architecture.md "Memory budget"). Constant
// time: what an element owns itself (a vector inside it) is the caller's to add, kept as a
// running total where elements vary in size, so asking stays cheap however much is held.
#include <cstddef>
#include <deque>
#include <map>
#include <vector>

namespace posefuse {

// A tree node's pointers and colour beside its value (libstdc++'s _Rb_tree_node_base).
inline constexpr std::size_t kMapNodeOverheadBytes = 4 * sizeof(void*);

template <class T>
std::size_t held_bytes(const std::vector<T>& values) {
  return values.capacity() * sizeof(T);
}

template <class T>
std::size_t held_bytes(const std::deque<T>& values) {
  return values.size() * sizeof(T);
}

template <class K, class V>
std::size_t held_bytes(const std::map<K, V>& values) {
  return values.size() * (sizeof(typename std::map<K, V>::value_type) + kMapNodeOverheadBytes);
}

}  // namespace posefuse
