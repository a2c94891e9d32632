#include "environment/track_layouts.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <utility>

#include "environment/random.hpp"
#include "environment/shapes.hpp"

namespace rilbed::environment {

std::string_view track_layout_kind_name(TrackLayoutKind kind) {
  switch (kind) {
    case TrackLayoutKind::kGrid: return "grid";
    case TrackLayoutKind::kTree: return "tree";
    case TrackLayoutKind::kLoopWithSpurs: return "loop";
  }
  return "?";
}

namespace {

// Draws from one seeded stream.
class Draw {
 public:
  explicit Draw(std::uint64_t seed) : rng_(seed) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform01(rng_); }
  int integer(int lo, int hi) {  // inclusive
    return lo + static_cast<int>(uniform01(rng_) * (hi - lo + 1));
  }
  bool chance(double p) { return uniform01(rng_) < p; }

 private:
  NoiseRng rng_;
};

TrackConfig segment(Vec2 a, Vec2 b, double width_m) {
  TrackConfig t;
  t.points_m = {a, b};
  t.width_m = width_m;
  return t;
}

// Whether segments ab and cd cross or come closer than `clearance`.
bool too_close(Vec2 a, Vec2 b, Vec2 c, Vec2 d, double clearance) {
  if (segment_blocks_sight(a, b, c, d)) return true;
  return std::min({distance_sq_to_segment(a, c, d), distance_sq_to_segment(b, c, d), distance_sq_to_segment(c, a, b),
                   distance_sq_to_segment(d, a, b)}) < clearance * clearance;
}

struct FieldBox {
  double x0, y0, x1, y1;
  bool contains(Vec2 p) const { return p.x >= x0 && p.x <= x1 && p.y >= y0 && p.y <= y1; }
};

std::vector<TrackConfig> grid_layout(Draw& draw, const FieldBox& box, double width_m) {
  const int nx = draw.integer(3, 5), ny = draw.integer(3, 5);
  auto point = [&](int i, int j) {
    return Vec2{box.x0 + (box.x1 - box.x0) * i / (nx - 1), box.y0 + (box.y1 - box.y0) * j / (ny - 1)};
  };
  // Links: (i, j)-(i+1, j) and (i, j)-(i, j+1).
  struct Link {
    int a, b;
  };
  std::vector<Link> links;
  auto index = [&](int i, int j) { return j * nx + i; };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (i + 1 < nx) links.push_back({index(i, j), index(i + 1, j)});
      if (j + 1 < ny) links.push_back({index(i, j), index(i, j + 1)});
    }
  // A random spanning tree (Kruskal over shuffled links), then each other link with
  // probability one half.
  for (std::size_t k = links.size(); k > 1; --k)
    std::swap(links[k - 1], links[static_cast<std::size_t>(draw.integer(0, static_cast<int>(k) - 1))]);
  std::vector<int> parent(static_cast<std::size_t>(nx * ny));
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int v) {
    while (parent[static_cast<std::size_t>(v)] != v)
      v = parent[static_cast<std::size_t>(v)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(v)])];
    return v;
  };
  std::vector<TrackConfig> tapes;
  for (const Link& l : links) {
    const int ra = root(l.a), rb = root(l.b);
    const bool in_tree = ra != rb;
    if (in_tree) parent[static_cast<std::size_t>(ra)] = rb;
    if (in_tree || draw.chance(0.5))
      tapes.push_back(segment(point(l.a % nx, l.a / nx), point(l.b % nx, l.b / nx), width_m));
  }
  return tapes;
}

std::vector<TrackConfig> tree_layout(Draw& draw, const FieldBox& box, double width_m) {
  std::vector<TrackConfig> tapes;
  struct Tip {
    Vec2 at;
    double heading_rad;
    int depth;
  };
  const Vec2 root{draw.uniform(box.x0 + 0.3 * (box.x1 - box.x0), box.x0 + 0.7 * (box.x1 - box.x0)), box.y0};
  std::vector<Tip> tips = {{root, kPi / 2, 0}};
  const double clearance = 0.1;
  while (!tips.empty() && tapes.size() < 14) {
    const Tip tip = tips.front();
    tips.erase(tips.begin());
    const int children = tip.depth == 0 ? 1 : draw.integer(1, 3);
    for (int c = 0; c < children; ++c) {
      for (int attempt = 0; attempt < 8; ++attempt) {
        // The first child goes on (within 20 degrees: no corner), the others branch off.
        const double turn = tip.depth == 0 ? 0.0
                            : c == 0       ? deg_to_rad(draw.uniform(-20.0, 20.0))
                                           : deg_to_rad(draw.uniform(45.0, 135.0)) * (draw.chance(0.5) ? 1.0 : -1.0);
        const double heading = tip.heading_rad + turn;
        const double length = draw.uniform(0.25, 0.5);
        const Vec2 end = tip.at + Vec2{std::cos(heading), std::sin(heading)} * length;
        if (!box.contains(end)) continue;
        bool clear = true;
        for (const TrackConfig& t : tapes) {
          const Vec2 a = t.points_m[0], b = t.points_m[1];
          // The branch may touch the tape it starts from at its start only.
          const bool from_here = (a - tip.at).norm() < 1e-9 || (b - tip.at).norm() < 1e-9;
          const Vec2 probe = from_here ? tip.at + (end - tip.at) * (clearance / length) : tip.at;
          if (too_close(probe, end, a, b, from_here ? 0.5 * clearance : clearance)) {
            clear = false;
            break;
          }
        }
        if (!clear) continue;
        tapes.push_back(segment(tip.at, end, width_m));
        if (tip.depth < 4) tips.push_back({end, heading, tip.depth + 1});
        break;
      }
    }
  }
  return tapes;
}

std::vector<TrackConfig> loop_layout(Draw& draw, const FieldBox& box, double width_m) {
  const Vec2 centre{0.5 * (box.x0 + box.x1), 0.5 * (box.y0 + box.y1)};
  const double rx = 0.3 * (box.x1 - box.x0), ry = 0.3 * (box.y1 - box.y0);
  TrackConfig loop;
  loop.width_m = width_m;
  loop.closed = true;
  const int corners = draw.integer(6, 10);
  for (int k = 0; k < corners; ++k) {
    const double a = 2 * kPi * (k + draw.uniform(-0.2, 0.2)) / corners;
    const double r = draw.uniform(0.85, 1.15);
    loop.points_m.push_back(centre + Vec2{rx * r * std::cos(a), ry * r * std::sin(a)});
  }
  std::vector<TrackConfig> tapes = {loop};
  const int spurs = draw.integer(2, 4);
  for (int s = 0; s < spurs; ++s) {
    for (int attempt = 0; attempt < 8; ++attempt) {
      const int k = draw.integer(0, corners - 1);
      const Vec2 a = loop.points_m[static_cast<std::size_t>(k)],
                 b = loop.points_m[static_cast<std::size_t>((k + 1) % corners)];
      const Vec2 start = a + (b - a) * draw.uniform(0.3, 0.7);
      const Vec2 along = (b - a) / (b - a).norm();
      Vec2 out{along.y, -along.x};  // the loop runs counter-clockwise: outwards is on the right
      if ((start - centre).dot(out) < 0) out = out * -1.0;
      const Vec2 end = start + out * draw.uniform(0.15, 0.3);
      if (!box.contains(end)) continue;
      bool clear = true;
      for (std::size_t t = 1; t < tapes.size(); ++t)
        if (too_close(start, end, tapes[t].points_m[0], tapes[t].points_m[1], 0.1)) clear = false;
      if (!clear) continue;
      tapes.push_back(segment(start, end, width_m));
      break;
    }
  }
  return tapes;
}

}  // namespace

std::vector<TrackConfig> make_track_layout(std::uint64_t seed, TrackLayoutKind kind,
                                           const TrackLayoutOptions& options) {
  const FieldBox box{options.margin_m, options.margin_m, options.field_width_m - options.margin_m,
                     options.field_height_m - options.margin_m};
  if (!(box.x1 - box.x0 >= 0.6 && box.y1 - box.y0 >= 0.6))
    throw std::invalid_argument("track layout: the field less its margins must be at least 0.6 m each way");
  Draw draw(mix64(seed ^ (static_cast<std::uint64_t>(kind) + 1) * 0x9e3779b97f4a7c15ULL));
  switch (kind) {
    case TrackLayoutKind::kGrid: return grid_layout(draw, box, options.tape_width_m);
    case TrackLayoutKind::kTree: return tree_layout(draw, box, options.tape_width_m);
    case TrackLayoutKind::kLoopWithSpurs: return loop_layout(draw, box, options.tape_width_m);
  }
  return {};
}

}  // namespace rilbed::environment
