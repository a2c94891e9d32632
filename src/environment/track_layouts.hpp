// Random track networks to explore, from a seed: the layouts a lab tapes down for paper
// 000's case study (§8-9), drawn fresh so that exploring and routing controllers are
// measured on networks nobody designed them for.
//   grid:  a lattice of 3-5 by 3-5 points, a random spanning tree of its links plus about
//          half of the others (missing edges make tees, corners and ends);
//   tree:  branches grown from a root, 1-3 children each (one going on within 20 degrees,
//          the others off at 45-135 degrees), never crossing or touching;
//   loop:  a closed tape round a perturbed ellipse with 2-4 spurs leaving it outwards.
// Every tape is a separate 2-point (or, for the loop, closed) polyline; TrackNetwork
// finds where they join.
#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "core/geometry.hpp"
#include "environment/static_map.hpp"

namespace rilbed::environment {

/// The families of layout make_track_layout draws.
enum class TrackLayoutKind { kGrid, kTree, kLoopWithSpurs };

/// "grid", "tree", "loop".
std::string_view track_layout_kind_name(TrackLayoutKind kind);

/// Where and how the layout is laid.
struct TrackLayoutOptions {
  double field_width_m = 2.0;   ///< the field, x from 0
  double field_height_m = 2.0;  ///< the field, y from 0
  double margin_m = 0.2;        ///< no tape nearer the field's walls than this
  double tape_width_m = 0.02;   ///< every tape's width
};

/// The tapes of one layout of `kind`, a pure function of `seed` and the options (the
/// same numbers on every machine). Throws std::invalid_argument when the field less its
/// margins is smaller than 0.6 m either way.
std::vector<TrackConfig> make_track_layout(std::uint64_t seed, TrackLayoutKind kind,
                                           const TrackLayoutOptions& options = {});

}  // namespace rilbed::environment
