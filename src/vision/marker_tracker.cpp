#include "vision/marker_tracker.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "core/geometry.hpp"
#include "vision/assignment.hpp"

namespace rilbed::vision {

namespace {

std::vector<int> checked_ids(const MarkerFamily& family, std::vector<int> ids) {
  if (ids.empty()) throw std::invalid_argument("the tracker needs at least one ID");
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  for (int id : ids) {
    if (!family.valid_id(id)) {
      throw std::invalid_argument("ID " + std::to_string(id) + " is not in family " + family.name());
    }
  }
  return ids;
}

// Two searches can find the same blob; keep one per place and size.
void append_unique(std::vector<Blob>& into, const std::vector<Blob>& found) {
  for (const Blob& b : found) {
    const double d = b.disc_diameter_px();
    const bool seen = std::any_of(into.begin(), into.end(), [&](const Blob& o) {
      return std::hypot(o.u - b.u, o.v - b.v) < 0.25 * d && std::abs(o.disc_diameter_px() - d) < 0.25 * d;
    });
    if (!seen) into.push_back(b);
  }
}

// The IDs the decoder compares with: the whole family when it is small enough, so that
// a marker of an unlisted ID is recognised as such.
std::vector<int> decoder_ids(const MarkerFamily& family, const std::vector<int>& listed) {
  constexpr int kMaxWholeFamily = 64;
  if (family.max_id() > kMaxWholeFamily) return listed;
  std::vector<int> all;
  for (int id = family.min_id(); id <= family.max_id(); ++id) all.push_back(id);
  return all;
}

DecoderConfig confirm_config(const TrackerConfig& config) {
  DecoderConfig c = config.decoder;
  c.samples = config.confirm_samples;
  return c;
}

// A detection of `blob` as `match`; the blob's disc scaled to the marker's outer size.
MarkerDetection make_detection(const Blob& blob, const CodeMatch& match, bool tracked, double threshold_grey) {
  const double disc_d = 2.0 * std::sqrt(std::abs(cv::determinant(blob.shape)));
  MarkerDetection d{match.id,          blob.u,         blob.v,
                    match.heading_deg, match.score,    disc_d / MarkerFamily::black_ring_outer_radius,
                    tracked,           threshold_grey, blob.shape};
  d.key_angle_rad = match.key_angle_rad;
  return d;
}

// The rays of TrackerConfig::nested_min_bright_rays: 16, from 0.3 of the blob's radius
// (clear of a hole at its centre) to 0.95 (short of its rim).
constexpr int kNestedRays = 16;
constexpr double kNestedRaysFrom = 0.3, kNestedRaysTo = 0.95;

// Whether `blob`'s dark disc belongs to a marker `marker_diameter_px` across (a track's),
// within a third either way: a robot's dark top around a marker is 1.5-2 times as wide.
bool similar_size(const Blob& blob, double marker_diameter_px) {
  const double ratio = blob.disc_diameter_px() / (MarkerFamily::black_ring_outer_radius * marker_diameter_px);
  return ratio > 0.75 && ratio < 1.33;
}

// Blobs at a confirmed marker's place are that marker: drop them.
void drop_confirmed(std::vector<Blob>& blobs, const std::vector<MarkerDetection>& confirmed) {
  std::erase_if(blobs, [&](const Blob& b) {
    return std::any_of(confirmed.begin(), confirmed.end(), [&](const MarkerDetection& d) {
      return std::hypot(d.u - b.u, d.v - b.v) < 0.25 * d.diameter_px;
    });
  });
}

}  // namespace

const char* fate_name(CandidateFate fate) {
  switch (fate) {
    case CandidateFate::kRefitFailed: return "refit failed";
    case CandidateFate::kLowScore: return "low score";
    case CandidateFate::kAmbiguous: return "ambiguous";
    case CandidateFate::kLevels: return "levels";
    case CandidateFate::kTemplate: return "template";
    case CandidateFate::kOccluded: return "occluded";
    case CandidateFate::kNotChosen: return "not chosen";
    case CandidateFate::kNamed: return "named";
  }
  return "?";
}

void MarkerTracker::log_verdict(const Blob& blob, CandidateFate fate, const CodeMatch* match, double runner_up) {
  if (verdicts_ == nullptr) return;
  CandidateVerdict v;
  v.u = blob.u;
  v.v = blob.v;
  v.diameter_px = blob.disc_diameter_px();
  v.fate = fate;
  if (match != nullptr) {
    v.id = match->id;
    v.score = match->score;
  }
  v.runner_up = runner_up;
  verdicts_->push_back(v);
}

MarkerTracker::MarkerTracker(MarkerFamily family, std::vector<int> ids, TrackerConfig config)
    : family_(std::move(family)),
      ids_(checked_ids(family_, std::move(ids))),
      config_(config),
      detector_(config.blobs),
      decoder_(family_, decoder_ids(family_, ids_), config.decoder),
      confirm_decoder_(family_, ids_, confirm_config(config)),
      templates_(family_, ids_, config.templates) {
  index_decoder();
}

void MarkerTracker::index_decoder() {
  decoder_index_.clear();
  for (int id : ids_) {
    const auto& all = decoder_.ids();
    decoder_index_.push_back(static_cast<int>(std::find(all.begin(), all.end(), id) - all.begin()));
  }
}

void MarkerTracker::set_config(const TrackerConfig& config) {
  config_ = config;
  detector_.set_config(config.blobs);
  decoder_ = Decoder(family_, decoder_ids(family_, ids_), config.decoder);
  confirm_decoder_ = Decoder(family_, ids_, confirm_config(config));
  templates_ = MarkerTemplates(family_, ids_, config.templates);
  index_decoder();
  reset();
}

void MarkerTracker::reset() {
  tracks_.clear();
  frames_since_full_ = 0;
}

cv::Mat MarkerTracker::to_grey(const cv::Mat& frame) {
  if (frame.empty()) throw std::invalid_argument("empty frame");
  if (frame.type() == CV_8UC1) return frame;
  if (frame.type() == CV_8UC3) {
    cv::cvtColor(frame, grey_buffer_, cv::COLOR_BGR2GRAY);
  } else if (frame.type() == CV_8UC4) {
    cv::cvtColor(frame, grey_buffer_, cv::COLOR_BGRA2GRAY);
  } else if (frame.depth() == CV_16U && frame.channels() == 1) {
    frame.convertTo(grey_buffer_, CV_8U, 1.0 / 257.0);
  } else {
    throw std::invalid_argument("unsupported frame type (expected 8-bit grey, BGR or BGRA)");
  }
  return grey_buffer_;
}

std::vector<MarkerDetection> MarkerTracker::assign(const cv::Mat& grey, const std::vector<Blob>& blobs, bool use_tracks,
                                                   const std::vector<int>& taken_ids) {
  // Buffers kept from frame to frame: a frame of 64 markers made 130 allocations here.
  const std::size_t columns = ids_.size();
  similarity_.assign(blobs.size() * columns, -1.0);
  if (matches_.size() < blobs.size()) matches_.resize(blobs.size());
  thresholds_.clear();
  passed_.assign(blobs.size(), false);
  named_discs_.assign(blobs.begin(), blobs.end());
  stats_.blobs += static_cast<int>(blobs.size());
  for (std::size_t b = 0; b < blobs.size(); ++b) {
    const Blob& blob = blobs[b];
    decoder_.sample(grey, blob, signal_);
    if (signal_.usable) ++stats_.decoded;
    thresholds_.push_back(0.5 * (signal_.black_level + signal_.white_level));
    std::vector<CodeMatch>& matches = matches_[b];
    decoder_.match_all(signal_, blob, matches);
    // Its own reading: the family's best match, and how far it stands above the next
    // explanation (another ID, or the same ID at another heading).
    std::size_t own = 0;
    for (std::size_t m = 1; m < matches.size(); ++m)
      if (matches[m].score > matches[own].score) own = m;
    double runner_up = matches[own].rival_score;
    for (std::size_t m = 0; m < matches.size(); ++m)
      if (m != own) runner_up = std::max(runner_up, matches[m].score);
    if (matches[own].score < config_.min_assign_score) {
      log_verdict(blob, CandidateFate::kLowScore, &matches[own], runner_up);
      unread_.push_back(blob);
      continue;
    }
    if (matches[own].score - runner_up < config_.ambiguity_margin) {
      ++stats_.declined;
      log_verdict(blob, CandidateFate::kAmbiguous, &matches[own], runner_up);
      unread_.push_back(blob);
      continue;
    }
    if (!decoder_.levels_agree(grey, blob, signal_, matches[own])) {  // not a printed marker's levels
      log_verdict(blob, CandidateFate::kLevels, &matches[own], runner_up);
      unread_.push_back(blob);
      continue;
    }
    if (!templates_.matches(grey, blob, matches[own].id, matches[own].key_angle_rad)) {  // not all of one
      log_verdict(blob, CandidateFate::kTemplate, &matches[own], runner_up);
      unread_.push_back(blob);
      continue;
    }
    if (find_band_across(grey, blob, signal_.black_level, signal_.white_level, config_.occluder).across) {
      ++stats_.occluded;
      log_verdict(blob, CandidateFate::kOccluded, &matches[own], runner_up);
      continue;  // not unread: it was read, and what lies across it is no robot's top
    }
    if (auto reread = reread_covered_rim(grey, blob, matches[own], thresholds_.back())) {
      named_discs_[b] = reread->first;
      matches[own] = reread->second;
    }
    passed_[b] = true;
    double* row = &similarity_[b * columns];
    for (std::size_t c = 0; c < columns; ++c) {
      if (static_cast<std::size_t>(decoder_index_[c]) != own) continue;  // only the ID its code reads
      const double score = matches[own].score;
      if (std::find(taken_ids.begin(), taken_ids.end(), ids_[c]) != taken_ids.end()) continue;
      row[c] = score;
      if (!use_tracks) continue;
      for (const Track& t : tracks_) {
        if (t.id != ids_[c]) continue;
        const cv::Point2d p = t.predicted();
        const double gate = config_.search_window_diameters * t.diameter_px + t.predicted_travel();
        if (std::hypot(blob.u - p.x, blob.v - p.y) < gate) row[c] += config_.track_bonus;
      }
    }
  }
  const std::vector<int> chosen = assign_max_similarity(similarity_.data(), static_cast<int>(blobs.size()),
                                                        static_cast<int>(columns), config_.min_assign_score);
  std::vector<MarkerDetection> out;
  for (std::size_t r = 0; r < blobs.size(); ++r) {
    if (verdicts_ != nullptr && passed_[r]) {
      const auto& m = matches_[r];
      const auto own =
          std::max_element(m.begin(), m.end(), [](const auto& x, const auto& y) { return x.score < y.score; });
      log_verdict(blobs[r], chosen[r] >= 0 ? CandidateFate::kNamed : CandidateFate::kNotChosen, &*own);
    }
    if (chosen[r] < 0) continue;
    out.push_back(make_detection(named_discs_[r], matches_[r][decoder_index_[chosen[r]]], false, thresholds_[r]));
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  return out;
}

std::vector<Blob> MarkerTracker::find_blobs(const cv::Mat& grey, std::vector<Blob>* fragments) {
  std::vector<Blob> blobs = detector_.detect(grey);
  settle_doubtful(grey, blobs, fragments);
  return blobs;
}

void MarkerTracker::settle_doubtful(const cv::Mat& grey, std::vector<Blob>& blobs, std::vector<Blob>* fragments) {
  // A doubtful blob's outline is re-found at its own threshold; what does not fit a
  // clean ellipse with a white ring around it is no marker anyone can read.
  std::erase_if(blobs, [&](Blob& blob) {
    if (!blob.doubtful) return false;
    ++stats_.refits;
    auto fit = fit_disc_edges(grey, blob, blob.threshold, config_.edge_fit);
    if (!fit) fit = fit_disc_edges(grey, blob, blob.threshold, config_.doubtful_edge_fit);
    if (!fit) {
      if (!config_.use_ring_search) {
        log_verdict(blob, CandidateFate::kRefitFailed);
        return true;
      }
      if (fragments != nullptr) {
        fragments->push_back(blob);
        return true;
      }
      const auto disc = rescue_fragment(grey, blob);
      if (!disc) {
        log_verdict(blob, CandidateFate::kRefitFailed);
        return true;
      }
      blob = *disc;
      return false;
    }
    if (fit->white_fraction < decoder_.config().min_white_ring_fraction) {
      log_verdict(blob, CandidateFate::kRefitFailed);
      return true;
    }
    ++stats_.refits_kept;
    blob = fit->blob;
    blob.doubtful = false;
    return false;
  });
}

std::optional<Blob> MarkerTracker::rescue_fragment(const cv::Mat& grey, const Blob& fragment) {
  if (fragment.disc_diameter_px() > config_.ring_search.max_fragment_diameter_px) return std::nullopt;
  ++stats_.ring_searches;
  const auto guess = search_ring(grey, fragment, config_.ring_search);
  if (!guess) return std::nullopt;
  const auto fit = fit_disc_edges(grey, *guess, fragment.threshold, config_.doubtful_edge_fit);
  if (!fit || fit->white_fraction < decoder_.config().min_white_ring_fraction) return std::nullopt;
  ++stats_.refits_kept;
  Blob disc = fit->blob;
  disc.doubtful = false;
  return disc;
}

void MarkerTracker::assign_rescued(const cv::Mat& grey, const std::vector<Blob>& fragments, bool use_tracks,
                                   std::vector<MarkerDetection>& found) {
  if (fragments.empty() || found.size() >= ids_.size()) return;
  std::vector<Blob> discs;
  for (const Blob& fragment : fragments) {
    if (auto disc = rescue_fragment(grey, fragment)) {
      append_unique(discs, {*disc});
    } else {
      log_verdict(fragment, CandidateFate::kRefitFailed);
    }
  }
  drop_confirmed(discs, found);
  if (discs.empty()) return;
  std::vector<int> taken;
  for (const MarkerDetection& d : found) taken.push_back(d.id);
  for (MarkerDetection& d : assign(grey, discs, use_tracks, taken)) found.push_back(std::move(d));
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
}

void MarkerTracker::assign_nested(const cv::Mat& grey, bool use_tracks, std::vector<MarkerDetection>& found) {
  if (!config_.search_inside_unread || unread_.empty() || found.size() >= ids_.size()) return;
  const std::vector<Blob> outer = std::move(unread_);
  unread_.clear();
  std::vector<Blob> inner;
  for (const Blob& b : outer) {
    // The smallest disc a marker has is min_diameter_px scaled to its dark disc; a blob
    // that cannot hold one inside its own outline holds no marker.
    const double least_disc = config_.blobs.min_diameter_px * MarkerFamily::black_ring_outer_radius;
    if (b.disc_diameter_px() < config_.nested_disc_ratio * least_disc) continue;
    if (config_.nested_min_bright_rays > 0 &&
        rays_crossing_bright(grey, b, kNestedRays, kNestedRaysFrom, kNestedRaysTo) < config_.nested_min_bright_rays) {
      continue;
    }
    // Its outline's box, searched with exact fills (detect_inside) for the discs it
    // encloses (the enclosing blob itself, when a seed lies on it, is dropped below).
    const double half_u = std::hypot(b.shape(0, 0), b.shape(0, 1)) + 2;
    const double half_v = std::hypot(b.shape(1, 0), b.shape(1, 1)) + 2;
    // Seeds only in its middle (nested_seed_fraction of its half extents): a marker on a
    // top lies there, and its hole and black slices seed it; most of the top's rim,
    // further out, is then not filled.
    auto box_of = [&](double fraction) {
      return cv::Rect(static_cast<int>(std::floor(b.u - fraction * half_u)),
                      static_cast<int>(std::floor(b.v - fraction * half_v)),
                      static_cast<int>(std::ceil(2 * fraction * half_u)) + 1,
                      static_cast<int>(std::ceil(2 * fraction * half_v)) + 1);
    };
    const cv::Rect box = box_of(1.0), seeds = box_of(config_.nested_seed_fraction);
    ++stats_.nested_searches;
    std::vector<Blob> here = detector_.detect_inside(grey, box, config_.nested_min_bright_outline, seeds);
    std::erase_if(here, [&](const Blob& h) { return h.disc_diameter_px() > 0.9 * b.disc_diameter_px(); });
    settle_doubtful(grey, here);
    append_unique(inner, here);
  }
  drop_confirmed(inner, found);
  if (inner.empty()) return;
  std::vector<int> taken;
  for (const MarkerDetection& d : found) taken.push_back(d.id);
  for (MarkerDetection& d : assign(grey, inner, use_tracks, taken)) found.push_back(std::move(d));
  unread_.clear();  // what failed inside is not searched again
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
}

std::vector<MarkerDetection> MarkerTracker::detect_full_frame(const cv::Mat& frame) {
  const cv::Mat grey = to_grey(frame);
  stats_ = FrameStats{};
  stats_.full_search = true;
  fragments_.clear();
  unread_.clear();
  auto found = assign(grey, find_blobs(grey, &fragments_), false);
  assign_rescued(grey, fragments_, false, found);
  assign_nested(grey, false, found);
  stats_.fills = detector_.take_fill_count();
  return found;
}

std::vector<Blob> MarkerTracker::search_window_inside(const cv::Mat& grey, const Track& track, cv::Rect window) {
  ++stats_.nested_searches;
  std::vector<Blob> inside = detector_.detect_inside(grey, window, config_.nested_min_bright_outline);
  std::erase_if(inside, [&](const Blob& b) { return !similar_size(b, track.diameter_px); });
  settle_doubtful(grey, inside);
  return inside;
}

std::optional<MarkerDetection> MarkerTracker::confirm(const cv::Mat& grey, const Track& track, const Blob& blob) {
  decoder_.sample(grey, blob, signal_);
  if (!signal_.usable) return std::nullopt;
  ++stats_.decoded;
  const CodeMatch m = decoder_.match_one(signal_, blob, track.id, track.predicted_heading_deg());
  if (m.score < config_.min_assign_score || m.score < track.score - config_.confirm_drop) return std::nullopt;
  if (!decoder_.levels_agree(grey, blob, signal_, m)) return std::nullopt;
  if (!templates_.matches(grey, blob, m.id, m.key_angle_rad)) return std::nullopt;
  const double threshold = 0.5 * (signal_.black_level + signal_.white_level);
  if (auto reread = reread_covered_rim(grey, blob, m, threshold))
    return make_detection(reread->first, reread->second, true, threshold);
  return make_detection(blob, m, true, threshold);
}

std::optional<std::pair<Blob, CodeMatch>> MarkerTracker::reread_covered_rim(const cv::Mat& grey, const Blob& blob,
                                                                            const CodeMatch& match,
                                                                            double threshold_grey) {
  if (config_.rim_refit.max_outliers <= 0) return std::nullopt;
  const auto fit = fit_disc_edges(grey, blob, threshold_grey, config_.rim_refit);
  if (!fit || fit->outliers == 0) return std::nullopt;
  if (std::hypot(fit->blob.u - blob.u, fit->blob.v - blob.v) < config_.rim_refit_min_shift_px) return std::nullopt;
  decoder_.sample(grey, fit->blob, reread_signal_);
  if (!reread_signal_.usable) return std::nullopt;
  const CodeMatch m = decoder_.match_one(reread_signal_, fit->blob, match.id, match.heading_deg);
  if (m.score < config_.min_assign_score) return std::nullopt;
  return std::pair{fit->blob, m};
}

Blob MarkerTracker::Track::predicted_disc() const {
  const cv::Point2d p = predicted();
  Blob disc;
  disc.u = p.x;
  disc.v = p.y;
  disc.shape = shape;
  disc.threshold = threshold_grey;
  return disc;
}

std::optional<MarkerDetection> MarkerTracker::confirm_by_edges(const cv::Mat& grey, const Track& track) {
  auto fit_near = [&](const DiscEdgeFitConfig& edge_fit) {
    Blob predicted = track.predicted_disc();
    auto fit = fit_disc_edges(grey, predicted, track.threshold_grey, edge_fit);
    if (!fit && (track.du != 0.0 || track.dv != 0.0)) {
      // It may have stopped or turned back (a bounce): where it was last is the other
      // cheap guess before a fill.
      predicted.u = track.u;
      predicted.v = track.v;
      fit = fit_disc_edges(grey, predicted, track.threshold_grey, edge_fit);
    }
    if (fit && fit->white_fraction < decoder_.config().min_white_ring_fraction) fit.reset();
    return fit;
  };
  // In the frames that only spot-check the code, the outline's centre and size first,
  // with the shape last fitted; the whole ellipse when that does not fit, or fits so
  // loosely that the shape has changed, and always in the frames that correlate (the
  // shape drifts as the marker crosses the field, and the heading is read through it).
  const bool spot_check = track.frames_since_correlated + 1 < config_.full_confirm_interval_frames;
  std::optional<DiscEdgeFit> fit;
  if (spot_check) fit = fit_near(config_.quick_edge_fit);
  const bool same_shape = fit && fit->residual <= config_.shape_refit_residual;
  if (!same_shape) fit = fit_near(config_.edge_fit);
  if (!fit) return std::nullopt;
  // As a full search's levels_agree: a cable's end across the white ring pulls the outline
  // fitted through it (on the stress set, a 53 px marker's centre 1.4 px off, another's
  // heading 6.6 degrees), where a full search declines the marker.
  if (!decoder_.white_ring_unbroken(grey, fit->blob, fit->black_level, fit->white_level)) return std::nullopt;
  const double threshold = 0.5 * (fit->black_level + fit->white_level);
  // The heading from the key's edges, and every slice's colour: a spot check. The key's
  // angle predicted in the shape's frame is the track's while the shape is the one it
  // kept.
  const double expected_key = same_shape
                                  ? track.predicted_key_angle_rad()
                                  : confirm_decoder_.key_angle_of_heading(fit->blob, track.predicted_heading_deg());
  const auto spot =
      confirm_decoder_.spot_check(grey, fit->blob, track.id, expected_key, fit->black_level, fit->white_level);
  if (spot && spot_check) {
    // The score stays the last correlation's.
    ++stats_.blobs;
    ++stats_.edge_fits;
    MarkerDetection d =
        make_detection(fit->blob, {track.id, track.score, spot->heading_deg, spot->key_angle_rad}, true, threshold);
    d.spot_checked = true;
    return d;
  }
  // The whole code correlated: a fresh score (and the heading, if the spot check failed).
  confirm_decoder_.sample_code(grey, fit->blob, fit->black_level, fit->white_level, signal_);
  if (!signal_.usable) return std::nullopt;
  CodeMatch m = confirm_decoder_.match_one(signal_, fit->blob, track.id, track.predicted_heading_deg());
  if (m.score < config_.min_assign_score || m.score < track.score - config_.confirm_drop) return std::nullopt;
  if (spot) {
    // The key's edges place the heading more precisely than the correlation of a
    // 60-sample signal (on the recorded clips 0.4-0.7 against 0.5-0.9 degrees RMS), and
    // every frame's heading then comes from the same measure.
    m.heading_deg = spot->heading_deg;
    m.key_angle_rad = spot->key_angle_rad;
  }
  ++stats_.blobs;
  ++stats_.decoded;
  ++stats_.edge_fits;
  return make_detection(fit->blob, m, true, threshold);
}

std::vector<MarkerDetection> MarkerTracker::process(const cv::Mat& frame) {
  const cv::Mat grey = to_grey(frame);
  stats_ = FrameStats{};
  unread_.clear();
  std::vector<Blob> blobs;  // found but not confirmed: decoded against the family
  // The markers confirmed near their tracks go straight into the result (its first
  // `confirmed` entries); those decoded from blobs follow.
  std::vector<MarkerDetection> found;
  found.reserve(tracks_.size() + 1);
  std::vector<int>& confirmed_ids = confirmed_ids_;
  confirmed_ids.clear();
  // Only tracks seen last frame try the edge fit, so only their areas are asked for.
  auto fits = [&](std::size_t i) { return config_.use_edge_fit && i < tracks_.size() && tracks_[i].missed == 0; };
  auto prefetch = [&](std::size_t i) {
    if (fits(i)) prefetch_disc_area(grey, tracks_[i].predicted_disc(), config_.edge_fit);
  };
  // Two markers ahead (about a microsecond of work): far enough for memory to answer,
  // near enough not to evict. On flushed 64-marker frames 2 ahead took 0.0346 ms, 3 ahead
  // 0.0348, 4 ahead 0.0350, 8 ahead (of 8 loaded) 0.0363.
  constexpr std::size_t kPrefetchAhead = 2;
  // The first markers' pixels are read at once with plain loads (many in flight), not
  // hinted: with nothing else waiting on memory yet, the CPU dropped most of a burst of
  // hints, and an 8-marker tracked frame took a third longer on a frame just written
  // to memory. Beyond these, hints a few markers ahead overlap the loads with the fits.
  // Few: the first fit waits for all of them (4 first: 0.0346 ms, 8: 0.0358, 16: 0.0383).
  constexpr std::size_t kLoadFirst = 4;
  for (std::size_t i = 0; i < kLoadFirst; ++i) {
    if (fits(i)) load_sink_ |= load_disc_area(grey, tracks_[i].predicted_disc(), config_.edge_fit);
  }
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    const Track& t = tracks_[i];
    if (i + kPrefetchAhead >= kLoadFirst) prefetch(i + kPrefetchAhead);  // loads while the ones before it are fitted
    // The cheap way first: the outline where the prediction puts it.
    if (config_.use_edge_fit && t.missed == 0) {
      if (auto d = confirm_by_edges(grey, t)) {
        found.push_back(std::move(*d));
        confirmed_ids.push_back(t.id);
        continue;
      }
    }
    // A track that missed frames coasts: its window moves on and widens with them.
    const cv::Point2d p = t.predicted();
    const double half = (config_.search_window_diameters + 0.5) * t.diameter_px + t.predicted_travel();
    const cv::Rect roi(static_cast<int>(std::floor(p.x - half)), static_cast<int>(std::floor(p.y - half)),
                       static_cast<int>(std::ceil(2 * half)) + 1, static_cast<int>(std::ceil(2 * half)) + 1);
    std::vector<Blob> near = detector_.detect_near(grey, roi, p, t.threshold_grey);
    settle_doubtful(grey, near);
    if (config_.search_inside_unread && t.missed == 0 && !(near.size() == 1 && similar_size(near[0], t.diameter_px))) {
      std::vector<Blob> inside = search_window_inside(grey, t, roi);
      if (!inside.empty()) near = std::move(inside);
    }
    if (near.size() == 1 && t.missed == 0) {
      ++stats_.blobs;
      if (auto d = confirm(grey, t, near[0])) {
        found.push_back(std::move(*d));
        confirmed_ids.push_back(t.id);
        continue;
      }
    }
    append_unique(blobs, near);
  }
  const std::size_t confirmed = found.size();
  drop_confirmed(blobs, found);
  if (!blobs.empty()) {
    for (MarkerDetection& d : assign(grey, blobs, true, confirmed_ids)) {
      d.tracked = true;
      found.push_back(std::move(d));
    }
  }

  const bool all_found = found.size() == ids_.size();
  ++frames_since_full_;
  if (tracks_.empty() || (!all_found && frames_since_full_ >= config_.full_search_interval_frames)) {
    frames_since_full_ = 0;
    fragments_.clear();
    unread_.clear();
    std::vector<Blob> more = find_blobs(grey, &fragments_);
    found.resize(confirmed);  // the blobs are assigned again, with the new ones
    drop_confirmed(more, found);
    append_unique(blobs, more);
    for (MarkerDetection& d : assign(grey, blobs, true, confirmed_ids)) found.push_back(std::move(d));
    assign_rescued(grey, fragments_, true, found);
    assign_nested(grey, true, found);
    stats_.full_search = true;
  }
  auto by_id = [](const auto& a, const auto& b) { return a.id < b.id; };
  if (!std::is_sorted(found.begin(), found.end(), by_id)) std::sort(found.begin(), found.end(), by_id);
  stats_.fills = detector_.take_fill_count();

  // Update the tracks: move the seen ones, coast the others, drop the long-lost.
  track_of_id_.assign(family_.max_id() + 1, -1);
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    ++tracks_[i].missed;
    track_of_id_[tracks_[i].id] = static_cast<int>(i);
  }
  for (const MarkerDetection& d : found) {
    const int index = track_of_id_[d.id];
    if (index < 0) {
      // Staggered by ID: of many markers found together, about one in the interval is
      // correlated in each frame.
      const int interval = std::max(1, config_.full_confirm_interval_frames);
      Track& t = tracks_.emplace_back(Track{d.id, d.u, d.v, 0.0, 0.0, d.diameter_px, d.threshold_grey, d.score,
                                            d.heading_deg, d.disc_shape, 0, d.id % interval});
      t.key_angle_rad = d.key_angle_rad;
      continue;
    }
    const auto it = tracks_.begin() + index;
    const int frames = it->missed;  // frames since the last sighting, >= 1
    it->du = (d.u - it->u) / frames;
    it->dv = (d.v - it->v) / frames;
    it->u = d.u;
    it->v = d.v;
    it->diameter_px = d.diameter_px;
    it->turn_deg = wrap_deg_180(d.heading_deg - it->heading_deg) / frames;
    // A spot check's angle is in the frame of the track's shape (its fit keeps it), so
    // the turn there is exact; after a fit of the whole outline the frame moved a little,
    // and the turn on screen stands in for it.
    it->key_turn_rad =
        d.spot_checked ? wrap_rad_pi(d.key_angle_rad - it->key_angle_rad) / frames : deg_to_rad(it->turn_deg);
    it->key_angle_rad = d.key_angle_rad;
    it->heading_deg = d.heading_deg;
    it->shape = d.disc_shape;
    it->threshold_grey = d.threshold_grey;
    // The reference score is set by a full decode and only lowered slowly by
    // confirmations, so a drifting code cannot ratchet its own bar down.
    it->score = d.tracked ? std::max(d.score, it->score - 0.01) : d.score;
    it->missed = 0;
    it->frames_since_correlated = d.spot_checked ? it->frames_since_correlated + 1 : 0;
  }
  std::erase_if(tracks_, [&](const Track& t) { return t.missed > config_.max_missed_frames; });
  return found;
}

std::vector<MarkerDetection> detect_markers(const cv::Mat& image, const MarkerFamily& family,
                                            const std::vector<int>& ids, const TrackerConfig& config) {
  MarkerTracker tracker(family, ids, config);
  return tracker.detect_full_frame(image);
}

}  // namespace rilbed::vision
