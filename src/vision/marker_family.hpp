// The one definition of rilbed's circular ID markers (paper 001, §4.1): slice angles,
// slice colours, ring radii, the ID code, and the ideal angular signal the decoder
// correlates against. The pattern generator, the synthetic camera and the decoder all
// read this file's definitions, so a printed marker, a rendered one and the decoder's
// model cannot disagree.
//
// Layout of a marker of outer radius R (all radii below are fractions of R):
//
//   r <= hole_radius            black inner hole
//   hole_radius < r <= code_outer_radius    the coded pie slices
//   code_outer_radius < r <= black_ring_outer_radius   black ring
//   black_ring_outer_radius < r <= 1        white outer ring
//
// The black ring closes the dark slices into one dark blob whose outer boundary is a
// circle; the white outer ring separates that blob from a dark floor, and merges with
// a light floor. So on a light or a dark floor the marker is one dark disc with a
// crisp circular edge, which is what the detector looks for.
//
// Slices are counted counter-clockwise as seen from above (as printed). Slice 0 is the
// wide "key" slice, always white, centred on the robot's forward direction; slices 1
// and last are always black; the slices between carry the code bits x1..xn, least
// significant first. ID = 1 + sum(x_i * 2^(i-1)), so 6UCP (n = 3) has IDs 1..8.
// (The paper's alpha vector gives odd numbers 1..15 but its text says IDs 1..8 and
// shows ID 6; rilbed follows the text.)
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace rilbed::vision {

/// One pie slice: its start and end angle in degrees, counter-clockwise from the
/// forward direction (start may be negative), and its colour.
struct MarkerSlice {
  double start_deg = 0.0;
  double end_deg = 0.0;
  bool white = false;
};

/// A family of k-slice uniform circular patterns (kUCP). 6UCP is the default.
class MarkerFamily {
 public:
  /// The paper's 6UCP: slices [85, 55, 55, 55, 55, 55] degrees, 3 code bits, IDs 1..8.
  static MarkerFamily six_ucp();

  /// A k-slice family, k >= 6: one key slice 1.5 units wide, two black guard slices
  /// and k-3 code slices of 1 unit each; IDs 1..2^(k-3). Every code is unique under
  /// rotation because the key is the only white run whose length is not a whole
  /// number of units. k = 9 gives 64 IDs, k = 12 gives 512 (at the cost of narrower
  /// slices: 12ucp slices are 28.8 degrees, so markers must be larger in the image).
  static MarkerFamily k_ucp(int slice_count);

  /// Looks a family up by name: "6ucp" (the paper's angles) or "<k>ucp" for k in 7..14.
  /// Throws std::invalid_argument naming the bad name; command-line code catches it
  /// and reports it as a usage error.
  static MarkerFamily by_name(std::string_view name);

  /// Family name as accepted by by_name ("6ucp", "9ucp", ...).
  const std::string& name() const { return name_; }
  /// Number of pie slices (k).
  int slice_count() const { return static_cast<int>(slice_deg_.size()); }
  /// Number of code bits (k - 3).
  int code_bits() const { return slice_count() - 3; }
  /// Smallest ID (always 1).
  int min_id() const { return 1; }
  /// Largest ID, 2^code_bits.
  int max_id() const { return 1 << code_bits(); }
  /// True when id is in [min_id, max_id].
  bool valid_id(int id) const { return id >= min_id() && id <= max_id(); }
  /// Slice widths in degrees, key slice first, counter-clockwise.
  const std::vector<double>& slice_widths_deg() const { return slice_deg_; }

  /// The slices of marker `id` with their angles and colours; the key slice is centred
  /// on 0 degrees. Throws std::out_of_range for an invalid id.
  std::vector<MarkerSlice> slices(int id) const;

  /// Colour of marker `id` at polar position (r, angle) in the marker frame, r as a
  /// fraction of the outer radius, angle in degrees counter-clockwise from forward.
  /// Returns 1.0 for white, 0.0 for black; points beyond r = 1 return -1 (not marker).
  double colour_at(int id, double r, double angle_deg) const;

  // The rings are wide enough (0.23 R black, 0.22 R white) to stay visible at 24 px
  // under about 1 px of blur; the coded annulus keeps 0.4 R for the signal.
  /// Radius of the black inner hole (fraction of R).
  static constexpr double hole_radius = 0.15;
  /// Outer radius of the coded slices (fraction of R).
  static constexpr double code_outer_radius = 0.55;
  /// Outer radius of the black ring, i.e. of the dark disc the detector finds.
  static constexpr double black_ring_outer_radius = 0.78;
  /// Radii (fractions of R) of the circles the decoder samples in the coded annulus;
  /// inside [hole_radius, code_outer_radius] with a margin for blur and centre error.
  static constexpr double sample_radii[3] = {0.27, 0.35, 0.43};

 private:
  MarkerFamily(std::string name, std::vector<double> slice_deg);
  std::string name_;
  std::vector<double> slice_deg_;
};

}  // namespace rilbed::vision
