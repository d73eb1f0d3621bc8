// Stable object ids across frames (docs/TRACKING.md): overlap with the previous frame's objects first,
// then merges, splits, and objects that come back, by 3D position.
#include "clutterseg/tracking.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace clutterseg {

namespace {

// Overlap is counted on every grid-th pixel of every grid-th row, a 160-column grid whatever the
// resolution (every 4th at 640x480, every 2nd at 320x240): the smallest objects still cover a dozen
// samples, and the tracker reads a sixteenth of a VGA frame.
int grid_step(int cols) { return std::max(1, cols / 160); }

// A part of an object is never much larger than the object: a return whose box exceeds the remembered
// one by more than this factor plus kSizeSlack along a sorted axis is another object.
constexpr float kSizeFactor = 1.5f, kSizeSlack = 0.02f;
// Velocity is learnt only while an object's pixel count changes less than this share between frames;
// beyond that its centroid moves because it is being occluded or revealed, not because it moves.
constexpr float kSteadyShare = 0.3f;
// The gates allow for a centroid moved by occlusion, a share of the object's box diagonal, but no more
// than this [m]: a box stretched by a few stray pixels must not open the gate across the table.
constexpr float kMaxHalfDiagonal = 0.1f;

Eigen::Vector3f sorted_extents(const OrientedBox& box) {
  Eigen::Vector3f e = box.extents;
  std::sort(e.data(), e.data() + 3, std::greater<float>());
  return e;
}

struct Overlap {
  int a = 0, b = 0;  // previous object a (1..), this frame's object b (1..); 0 = no object
  int count = 0;     // grid pixels
};

}  // namespace

void Tracker::forget() {
  tracks_.clear();
  previous_grid_.clear();
  previous_ids_.clear();
  size_ = cv::Size();
}

void Tracker::reset() {
  forget();
  frame_ = 0;
  next_id_ = 1;
}

int Tracker::new_id() {
  const int max_id = std::max(1, params_.max_id);
  for (int tries = 0; tries < max_id; ++tries) {
    const int id = next_id_;
    next_id_ = next_id_ >= max_id ? 1 : next_id_ + 1;
    if (std::none_of(tracks_.begin(), tracks_.end(), [&](const Track& t) { return t.id == id; })) return id;
  }
  throw Error("tracking: more objects at once than tracking.max_id (" + std::to_string(max_id) + ") ids");
}

std::vector<HiddenObject> Tracker::update(cv::Mat& labels, std::vector<Object>& objects) {
  if (labels.type() != CV_32S) throw Error("tracking: labels must be CV_32S");
  ++frame_;
  if (labels.size() != size_) forget();
  size_ = labels.size();
  const int m = static_cast<int>(objects.size());
  const int mp = static_cast<int>(previous_ids_.size());

  // Pixel overlap of previous and current objects on the grid, as run-length counted pairs.
  const int stride = grid_step(labels.cols);
  const int gw = (labels.cols + stride - 1) / stride, gh = (labels.rows + stride - 1) / stride;
  std::vector<int> grid(static_cast<size_t>(gw) * static_cast<size_t>(gh));
  const bool have_previous = previous_grid_.size() == grid.size();
  std::vector<Overlap> runs;
  {
    Overlap run;
    for (int gy = 0; gy < gh; ++gy) {
      const int* lab = labels.ptr<int>(gy * stride);
      int* cur = grid.data() + static_cast<size_t>(gy) * static_cast<size_t>(gw);
      const int* prev = have_previous ? previous_grid_.data() + static_cast<size_t>(gy) * static_cast<size_t>(gw) : nullptr;
      for (int gx = 0; gx < gw; ++gx) {
        const int raw = lab[gx * stride];
        const int b = raw > 0 && raw <= m ? raw : 0;
        const int a = prev ? prev[gx] : 0;
        cur[gx] = b;
        if (a == run.a && b == run.b) {
          ++run.count;
        } else {
          if (run.count > 0) runs.push_back(run);
          run = {a, b, 1};
        }
      }
    }
    if (run.count > 0) runs.push_back(run);
  }
  std::sort(runs.begin(), runs.end(), [](const Overlap& x, const Overlap& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });
  std::vector<Overlap> pairs;
  for (const Overlap& r : runs) {
    if (!pairs.empty() && pairs.back().a == r.a && pairs.back().b == r.b) pairs.back().count += r.count;
    else pairs.push_back(r);
  }
  std::vector<int> area_prev(static_cast<size_t>(mp) + 1, 0), area_cur(static_cast<size_t>(m) + 1, 0);
  for (const Overlap& p : pairs) {
    if (p.a <= mp) area_prev[static_cast<size_t>(p.a)] += p.count;
    area_cur[static_cast<size_t>(p.b)] += p.count;
  }

  // Tracks by index; the previous frame's objects are tracks too (their ids are alive).
  const auto index_of = [&](int id) {
    const auto it = std::lower_bound(tracks_.begin(), tracks_.end(), id, [](const Track& t, int v) { return t.id < v; });
    return it != tracks_.end() && it->id == id ? static_cast<int>(it - tracks_.begin()) : -1;
  };
  std::vector<int> track_of_prev(static_cast<size_t>(mp) + 1, -1);
  for (int a = 1; a <= mp; ++a) track_of_prev[static_cast<size_t>(a)] = index_of(previous_ids_[static_cast<size_t>(a - 1)]);

  const int nt = static_cast<int>(tracks_.size());
  std::vector<int> object_of(static_cast<size_t>(nt), -1), track_of(static_cast<size_t>(m), -1);
  std::vector<char> retired(static_cast<size_t>(nt), 0);
  std::vector<int> split_from(static_cast<size_t>(m), 0);
  std::vector<Eigen::Vector3f> extents(static_cast<size_t>(m));
  for (int j = 0; j < m; ++j) extents[static_cast<size_t>(j)] = sorted_extents(objects[static_cast<size_t>(j)].box);

  const auto unseen = [&](const Track& t) { return std::max(1, frame_ - t.last_seen); };
  const auto predicted = [&](const Track& t) { return Eigen::Vector3f(t.centroid + t.velocity * static_cast<float>(unseen(t))); };
  const auto distance = [&](const Track& t, int j) { return (objects[static_cast<size_t>(j)].centroid - predicted(t)).norm(); };
  const auto reach = [&](const Track& t) { return static_cast<float>(params_.max_step * std::sqrt(static_cast<double>(unseen(t)))); };
  const auto assign = [&](int t, int j) {
    object_of[static_cast<size_t>(t)] = j;
    track_of[static_cast<size_t>(j)] = t;
  };

  // 1) Overlap, IoU first, within the 3D gate.
  {
    struct Candidate {
      double iou;
      int t, j;
    };
    std::vector<Candidate> candidates;
    for (const Overlap& p : pairs) {
      if (p.a == 0 || p.b == 0 || p.a > mp) continue;
      const int t = track_of_prev[static_cast<size_t>(p.a)], j = p.b - 1;
      if (t < 0) continue;
      const Track& track = tracks_[static_cast<size_t>(t)];
      // A quarter of the larger diagonal: partial occlusion moves a centroid that much; an object that
      // moved off and uncovered another one leaves its old pixels to an object farther away.
      const float diag = std::max(track.diagonal, extents[static_cast<size_t>(j)].norm());
      if (distance(track, j) > reach(track) + std::min(0.25f * diag, kMaxHalfDiagonal)) continue;
      const double iou = p.count / static_cast<double>(area_prev[static_cast<size_t>(p.a)] + area_cur[static_cast<size_t>(p.b)] - p.count);
      candidates.push_back({iou, t, j});
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
      return x.iou != y.iou ? x.iou > y.iou : x.t != y.t ? x.t < y.t : x.j < y.j;
    });
    for (const Candidate& c : candidates)
      if (object_of[static_cast<size_t>(c.t)] < 0 && track_of[static_cast<size_t>(c.j)] < 0) assign(c.t, c.j);
  }

  // The largest overlap of previous object a with a current object, and of current object b with a
  // previous one (pairs are sorted by a).
  std::vector<Overlap> best_of_prev(static_cast<size_t>(mp) + 1), best_of_cur(static_cast<size_t>(m) + 1);
  for (const Overlap& p : pairs) {
    if (p.a == 0 || p.b == 0 || p.a > mp) continue;
    if (p.count > best_of_prev[static_cast<size_t>(p.a)].count) best_of_prev[static_cast<size_t>(p.a)] = p;
    if (p.count > best_of_cur[static_cast<size_t>(p.b)].count) best_of_cur[static_cast<size_t>(p.b)] = p;
  }
  const auto share = [&](int count, int area) { return area > 0 && count > params_.merge_share * area; };

  // 2) Merges: an unmatched previous object inside a current object that kept another id: most of its
  //    pixels, or (when it moves) its predicted centroid inside that object's box. The table and the
  //    background host nothing (an object lifted away is gone, not merged into the table).
  const auto can_host = [&](int j) {
    const Object& o = objects[static_cast<size_t>(j)];
    return !o.support && !o.background && track_of[static_cast<size_t>(j)] >= 0;
  };
  const auto inside_box = [&](const Eigen::Vector3f& p, int j) {
    const OrientedBox& box = objects[static_cast<size_t>(j)].box;
    const Eigen::Vector3f local = box.axes.transpose() * (p - box.center);
    return (local.cwiseAbs().array() <= (0.5f * box.extents).array() + 0.01f).all();
  };
  for (int a = 1; a <= mp; ++a) {
    const int t = track_of_prev[static_cast<size_t>(a)];
    if (t < 0 || object_of[static_cast<size_t>(t)] >= 0) continue;
    const Overlap& best = best_of_prev[static_cast<size_t>(a)];
    int j = best.count > 0 && share(best.count, area_prev[static_cast<size_t>(a)]) && can_host(best.b - 1) ? best.b - 1 : -1;
    if (j < 0) {
      const Eigen::Vector3f p = predicted(tracks_[static_cast<size_t>(t)]);
      float nearest = 0;
      for (int k = 0; k < m; ++k) {
        if (!can_host(k) || !inside_box(p, k)) continue;
        const float d = (objects[static_cast<size_t>(k)].centroid - p).norm();
        if (j < 0 || d < nearest) j = k, nearest = d;
      }
    }
    if (j < 0) continue;
    const int host = track_of[static_cast<size_t>(j)];
    Track& track = tracks_[static_cast<size_t>(t)];
    Track& hosting = tracks_[static_cast<size_t>(host)];
    if (track.split_from == hosting.id) {  // a fragment back in the object it split from: dropped
      retired[static_cast<size_t>(t)] = 1;
    } else if (track.pixels > hosting.pixels) {
      // The merged object carries the id of the larger object (as last seen alone): the one it mostly
      // shows. The other becomes its guest, with the guests it had.
      for (int g = 0; g < nt; ++g)
        if (tracks_[static_cast<size_t>(g)].merged_into == hosting.id && object_of[static_cast<size_t>(g)] < 0)
          tracks_[static_cast<size_t>(g)].merged_into = track.id;
      hosting.merged_into = track.id;
      object_of[static_cast<size_t>(host)] = -1;
      assign(t, j);
    } else {
      track.merged_into = hosting.id;
    }
  }

  // A remembered track may take object j: near its predicted centroid, and no larger than it was.
  const auto fits = [&](const Track& t, int j) {
    const Eigen::Vector3f& e = extents[static_cast<size_t>(j)];
    for (int k = 0; k < 3; ++k)
      if (e[k] > kSizeFactor * t.extents[k] + kSizeSlack) return false;
    return distance(t, j) <= reach(t) + std::min(0.5f * t.diagonal, kMaxHalfDiagonal);
  };
  const auto free_track = [&](int t) { return object_of[static_cast<size_t>(t)] < 0 && !retired[static_cast<size_t>(t)]; };

  // 3) Splits. A host with merged guests that comes apart: the host and its guests take the parts by 3D
  //    distance to where each was last seen alone (hosts keep that position while merged).
  std::vector<int> order(static_cast<size_t>(m));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return area_cur[static_cast<size_t>(x) + 1] > area_cur[static_cast<size_t>(y) + 1]; });
  const auto part_of = [&](int j) {  // the previous object holding most of object j, or 0
    const Overlap& best = best_of_cur[static_cast<size_t>(j) + 1];
    return best.count > 0 && share(best.count, area_cur[static_cast<size_t>(j) + 1]) ? best.a : 0;
  };
  std::vector<int> guests;  // merged tracks not matched by overlap
  for (int t = 0; t < nt; ++t)
    if (tracks_[static_cast<size_t>(t)].merged_into != 0 && free_track(t)) guests.push_back(t);
  const auto overlaps = [&](int a, int j) {  // previous object a and current object j share grid pixels
    const auto it = std::lower_bound(pairs.begin(), pairs.end(), Overlap{a, j + 1, 0},
                                     [](const Overlap& x, const Overlap& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });
    return it != pairs.end() && it->a == a && it->b == j + 1;
  };
  for (int a = 1; a <= mp && !guests.empty(); ++a) {
    const int host = track_of_prev[static_cast<size_t>(a)];
    if (host < 0 || object_of[static_cast<size_t>(host)] < 0) continue;
    std::vector<int> claimants = {host}, parts;
    for (int t : guests)
      if (tracks_[static_cast<size_t>(t)].merged_into == tracks_[static_cast<size_t>(host)].id && free_track(t)) claimants.push_back(t);
    if (claimants.size() < 2) continue;
    // Parts: the host's match and every unmatched object that shares pixels with the host's region.
    for (int j : order)
      if (track_of[static_cast<size_t>(j)] == host || (track_of[static_cast<size_t>(j)] < 0 && overlaps(a, j))) parts.push_back(j);
    if (parts.size() < 2) continue;
    struct Candidate {
      float d;
      int t, j;
    };
    std::vector<Candidate> candidates;
    for (int t : claimants)
      for (int j : parts)
        if (t == host || fits(tracks_[static_cast<size_t>(t)], j)) candidates.push_back({distance(tracks_[static_cast<size_t>(t)], j), t, j});
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
      return x.d != y.d ? x.d < y.d : x.t != y.t ? x.t < y.t : x.j < y.j;
    });
    track_of[static_cast<size_t>(object_of[static_cast<size_t>(host)])] = -1;
    object_of[static_cast<size_t>(host)] = -1;
    for (const Candidate& c : candidates)
      if (object_of[static_cast<size_t>(c.t)] < 0 && track_of[static_cast<size_t>(c.j)] < 0) assign(c.t, c.j);
  }
  // Any other unmatched object mostly inside a previous object that kept its id is a split part.
  for (int j = 0; j < m; ++j) {
    const int a = part_of(j);
    if (track_of[static_cast<size_t>(j)] >= 0 || a == 0) continue;
    const int host = track_of_prev[static_cast<size_t>(a)];
    if (host >= 0 && object_of[static_cast<size_t>(host)] >= 0) split_from[static_cast<size_t>(j)] = tracks_[static_cast<size_t>(host)].id;
  }

  // 4) Returns: remembered tracks (and previous objects that lost their overlap) by 3D distance.
  {
    struct Candidate {
      float d;
      int t, j;
    };
    std::vector<Candidate> candidates;
    for (int j = 0; j < m; ++j) {
      if (track_of[static_cast<size_t>(j)] >= 0) continue;
      for (int t = 0; t < nt; ++t)
        if (free_track(t) && fits(tracks_[static_cast<size_t>(t)], j)) candidates.push_back({distance(tracks_[static_cast<size_t>(t)], j), t, j});
    }
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
      return x.d != y.d ? x.d < y.d : x.t != y.t ? x.t < y.t : x.j < y.j;
    });
    for (const Candidate& c : candidates)
      if (object_of[static_cast<size_t>(c.t)] < 0 && track_of[static_cast<size_t>(c.j)] < 0) assign(c.t, c.j);
  }

  // What the objects report, read before the tracks learn this frame.
  std::vector<int> id_of(static_cast<size_t>(m), 0), age(static_cast<size_t>(m), 1), missed(static_cast<size_t>(m), 0);
  std::vector<int> origin = split_from;
  for (int t = 0; t < nt; ++t) {
    const int j = object_of[static_cast<size_t>(t)];
    if (j < 0) continue;
    const Track& track = tracks_[static_cast<size_t>(t)];
    id_of[static_cast<size_t>(j)] = track.id;
    age[static_cast<size_t>(j)] = frame_ - track.first_frame + 1;
    missed[static_cast<size_t>(j)] = std::max(0, frame_ - track.last_seen - 1);
    origin[static_cast<size_t>(j)] = track.split_from;
  }

  // Matched tracks learn the new position and velocity, except hosts of merged objects: they keep where
  // they were last seen alone, for when the merge comes apart. The rest are remembered or forgotten.
  std::vector<int> guest_hosts;
  for (int t = 0; t < nt; ++t)
    if (free_track(t) && tracks_[static_cast<size_t>(t)].merged_into != 0) guest_hosts.push_back(tracks_[static_cast<size_t>(t)].merged_into);
  for (int t = 0; t < nt; ++t) {
    Track& track = tracks_[static_cast<size_t>(t)];
    const int j = object_of[static_cast<size_t>(t)];
    if (j < 0) continue;
    track.merged_into = 0;
    const Object& o = objects[static_cast<size_t>(j)];
    if (std::find(guest_hosts.begin(), guest_hosts.end(), track.id) != guest_hosts.end()) {
      // Hosting: its own position moves with the merged object (a carried pair), its size stays.
      if (track.hosting) track.centroid += o.centroid - track.seen;
      track.hosting = true;
      track.seen = o.centroid;
      track.last_seen = frame_;
      continue;
    }
    track.hosting = false;
    track.seen = o.centroid;
    const int gap = unseen(track);
    const bool steady = std::abs(o.pixel_count - track.pixels) < kSteadyShare * std::max(o.pixel_count, track.pixels);
    if (steady && track.merged_into == 0) {
      Eigen::Vector3f v = 0.5f * (track.velocity + (o.centroid - track.centroid) / static_cast<float>(gap));
      const float limit = static_cast<float>(params_.max_step);
      if (v.norm() > limit) v *= limit / v.norm();
      track.velocity = v;
    }
    track.merged_into = 0;
    track.centroid = o.centroid;
    track.box = o.box;
    // An object that shrank by more than the steady share is being hidden: it keeps the size it had, so
    // that it can come back whole.
    const bool shrinking = o.pixel_count < (1 - kSteadyShare) * track.pixels;
    track.extents = shrinking ? track.extents.cwiseMax(extents[static_cast<size_t>(j)]) : extents[static_cast<size_t>(j)];
    track.diagonal = track.extents.norm();
    track.pixels = o.pixel_count;
    track.last_seen = frame_;
  }
  std::vector<Track> kept;
  kept.reserve(tracks_.size() + static_cast<size_t>(m));
  for (int t = 0; t < nt; ++t)
    if (!retired[static_cast<size_t>(t)] && frame_ - tracks_[static_cast<size_t>(t)].last_seen <= std::max(0, params_.max_missed))
      kept.push_back(tracks_[static_cast<size_t>(t)]);
  tracks_ = std::move(kept);

  // 5) New objects: ids never used in the stream (until they wrap at max_id).
  for (int j = 0; j < m; ++j) {
    if (id_of[static_cast<size_t>(j)] != 0) continue;
    const Object& o = objects[static_cast<size_t>(j)];
    Track track;
    track.id = new_id();
    track.first_frame = track.last_seen = frame_;
    track.split_from = split_from[static_cast<size_t>(j)];
    track.centroid = track.seen = o.centroid;
    track.box = o.box;
    track.extents = extents[static_cast<size_t>(j)];
    track.diagonal = track.extents.norm();
    track.pixels = o.pixel_count;
    tracks_.push_back(track);
    id_of[static_cast<size_t>(j)] = track.id;
  }
  std::sort(tracks_.begin(), tracks_.end(), [](const Track& x, const Track& y) { return x.id < y.id; });
  // A guest whose host is gone is just unseen.
  for (Track& track : tracks_)
    if (track.merged_into != 0 && track.last_seen < frame_ && index_of(track.merged_into) < 0) track.merged_into = 0;

  // The label image in place, run by run (labels come in long runs).
  std::vector<int> lut(static_cast<size_t>(m) + 1, 0);
  for (int j = 0; j < m; ++j) lut[static_cast<size_t>(j) + 1] = id_of[static_cast<size_t>(j)];
  for (int y = 0; y < labels.rows; ++y) {
    int* lab = labels.ptr<int>(y);
    for (int x = 0; x < labels.cols;) {
      const int end = run_end(lab, x, labels.cols);
      const int raw = lab[x];
      std::fill(lab + x, lab + end, raw > 0 && raw <= m ? lut[static_cast<size_t>(raw)] : 0);
      x = end;
    }
  }

  std::vector<HiddenObject> hidden;
  for (const Track& track : tracks_) {
    if (track.last_seen == frame_) continue;
    hidden.push_back({track.id, frame_ - track.first_frame + 1, frame_ - track.last_seen, track.merged_into, track.centroid, track.box});
  }
  for (int j = 0; j < m; ++j) {
    Object& o = objects[static_cast<size_t>(j)];
    o.id = id_of[static_cast<size_t>(j)];
    o.age = age[static_cast<size_t>(j)];
    o.frames_missed = missed[static_cast<size_t>(j)];
    o.split_from = origin[static_cast<size_t>(j)];
    o.merged_with.clear();
    for (const HiddenObject& h : hidden)
      if (h.merged_into == o.id) o.merged_with.push_back(h.id);
  }
  std::sort(objects.begin(), objects.end(), [](const Object& x, const Object& y) { return x.id < y.id; });
  previous_grid_ = std::move(grid);
  previous_ids_ = std::move(id_of);
  return hidden;
}

}  // namespace clutterseg
