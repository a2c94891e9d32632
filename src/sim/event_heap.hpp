// The coordinator's schedule: an indexed binary min-heap of next-event times.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include "sim/time.hpp"

namespace rilbed::sim::detail {

/// Items 0..n-1 (atomic indices in flat order), each with a next-event time, ordered by
/// (time, index) so that ties are broken by flat order. update() re-keys one item in
/// O(log n); collect_at() lists every item due at the earliest time in O(due).
/// Internal to the coordinator; not thread-safe.
class EventHeap {
 public:
  /// Replaces the contents: item i gets time `times_us[i]`.
  void assign(std::vector<TimeUs> times_us) {
    times_us_ = std::move(times_us);
    const std::size_t n = times_us_.size();
    heap_.resize(n);
    position_.resize(n);
    for (std::size_t i = 0; i < n; ++i) heap_[i] = position_[i] = i;
    for (std::size_t pos = n / 2; pos-- > 0;) sift_down(pos);
  }

  /// Number of items.
  std::size_t size() const { return heap_.size(); }
  /// The earliest time, or kInfinity when empty.
  TimeUs top_time_us() const { return heap_.empty() ? kInfinity : times_us_[heap_[0]]; }
  /// The time of `item`.
  TimeUs time_us(std::size_t item) const { return times_us_[item]; }

  /// Gives `item` a new time.
  void update(std::size_t item, TimeUs t_us) {
    const TimeUs old_t_us = times_us_[item];
    times_us_[item] = t_us;
    if (t_us < old_t_us)
      sift_up(position_[item]);
    else
      sift_down(position_[item]);
  }

  /// Sets `item`'s time without restoring heap order (O(1)); reheap() must follow before
  /// any other call. For a step that re-keys a large share of the items at once, where
  /// one O(n) reheap beats k sifts of O(log n) with a cache miss at each level.
  void set_time_unordered(std::size_t item, TimeUs t_us) { times_us_[item] = t_us; }
  /// Restores heap order after set_time_unordered() calls (Floyd's heap construction, O(n)).
  void reheap() {
    for (std::size_t pos = heap_.size() / 2; pos-- > 0;) sift_down(pos);
  }

  /// Appends to `items`, in increasing item order, every item whose time is `t_us`, by one
  /// pass over all items (O(n), sequential): cheaper than collect_at() and a sort when a
  /// large share of the items is due.
  void collect_all_at(TimeUs t_us, std::vector<std::size_t>& items) const {
    for (std::size_t i = 0; i < times_us_.size(); ++i)
      if (times_us_[i] == t_us) items.push_back(i);
  }

  /// Appends to `items` every item whose time is `t_us`, in no particular order.
  /// Only the subtrees whose root is due are visited (heap order).
  /// Stops early, returning false, once more than `limit` items are listed (some of the
  /// due items are then listed, in no useful order): a caller that handles many due items
  /// another way (collect_all_at) need not walk them all through the heap. True when all
  /// due items were listed.
  bool collect_at(TimeUs t_us, std::vector<std::size_t>& items, std::size_t limit = static_cast<std::size_t>(-1)) {
    if (heap_.empty() || times_us_[heap_[0]] != t_us) return true;
    const std::size_t first = items.size();
    stack_.clear();
    stack_.push_back(0);
    while (!stack_.empty()) {
      const std::size_t pos = stack_.back();
      stack_.pop_back();
      items.push_back(heap_[pos]);
      if (items.size() - first > limit) return false;
      for (std::size_t child = 2 * pos + 1; child <= 2 * pos + 2 && child < heap_.size(); ++child)
        if (times_us_[heap_[child]] == t_us) stack_.push_back(child);
    }
    return true;
  }

 private:
  bool before(std::size_t a, std::size_t b) const {
    return times_us_[a] != times_us_[b] ? times_us_[a] < times_us_[b] : a < b;
  }
  void place(std::size_t pos, std::size_t item) {
    heap_[pos] = item;
    position_[item] = pos;
  }
  void sift_up(std::size_t pos) {
    const std::size_t item = heap_[pos];
    while (pos > 0) {
      const std::size_t parent = (pos - 1) / 2;
      if (!before(item, heap_[parent])) break;
      place(pos, heap_[parent]);
      pos = parent;
    }
    place(pos, item);
  }
  void sift_down(std::size_t pos) {
    const std::size_t item = heap_[pos];
    const std::size_t n = heap_.size();
    for (;;) {
      std::size_t child = 2 * pos + 1;
      if (child >= n) break;
      if (child + 1 < n && before(heap_[child + 1], heap_[child])) ++child;
      if (!before(heap_[child], item)) break;
      place(pos, heap_[child]);
      pos = child;
    }
    place(pos, item);
  }

  std::vector<TimeUs> times_us_;       // item -> next time
  std::vector<std::size_t> heap_;      // heap position -> item
  std::vector<std::size_t> position_;  // item -> heap position
  std::vector<std::size_t> stack_;     // scratch for collect_at
};

}  // namespace rilbed::sim::detail
