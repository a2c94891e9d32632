#include "environment/spatial_grid.hpp"

namespace rilbed::environment {

SpatialGrid::SpatialGrid(GridGeometry geometry) : geometry_(geometry), head_(geometry.cell_count(), -1) {}

void SpatialGrid::clear_occupied() {
  // Every non-empty cell holds at least one item, so clearing the items' cells clears
  // them all without touching the (many more) empty cells.
  for (const std::int32_t cell : cell_of_) head_[static_cast<std::size_t>(cell)] = -1;
}

void SpatialGrid::resize_items(std::size_t count) {
  next_.resize(count);
  cell_of_.resize(count);
}

void SpatialGrid::link(std::int32_t item, int cell) {
  const auto i = static_cast<std::size_t>(item);
  cell_of_[i] = cell;
  next_[i] = head_[static_cast<std::size_t>(cell)];
  head_[static_cast<std::size_t>(cell)] = item;
}

void SpatialGrid::unlink(std::int32_t item) {
  const auto i = static_cast<std::size_t>(item);
  std::int32_t* slot = &head_[static_cast<std::size_t>(cell_of_[i])];
  while (*slot != item) slot = &next_[static_cast<std::size_t>(*slot)];
  *slot = next_[i];
}

void SpatialGrid::rebuild(std::span<const Vec2> positions) {
  rebuild(positions.size(), [&](std::size_t i) { return positions[i]; });
}

void SpatialGrid::push_back(Vec2 p) {
  const auto item = static_cast<std::int32_t>(cell_of_.size());
  resize_items(cell_of_.size() + 1);
  link(item, geometry_.cell_of(p));
}

void SpatialGrid::move(std::size_t item, Vec2 p) {
  const int cell = geometry_.cell_of(p);
  if (cell == cell_of_[item]) return;
  unlink(static_cast<std::int32_t>(item));
  link(static_cast<std::int32_t>(item), cell);
}

}  // namespace rilbed::environment
