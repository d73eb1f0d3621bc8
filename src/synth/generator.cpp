#include "clutterseg/synth/generator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <random>

#include "clutterseg/synth/sensor.hpp"

namespace clutterseg::synth {

namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr double kDeg = M_PI / 180;

const std::vector<PresetInfo> kPresets = {
    {"occluded-box", "a wide box split in two by a narrow, taller box in front of it (paper Fig. 5)", 2, 2},
    {"cup", "one open cup: inner and outer wall, rim and bottom", 1, 1},
    {"bowl", "one open bowl: a spherical shell with inner and outer side", 1, 1},
    {"lying-cylinder-occluded", "a cylinder lying across the view, cut in two by a box in front (paper Fig. 6)", 2, 2},
    {"side-by-side-boxes", "two boxes touching side by side", 2, 2},
    {"staircase", "three books stacked, each shifted back: a staircase of parallel faces", 3, 3},
    {"sphere", "one sphere resting on the table", 1, 1},
    {"boxes", "Table II family: 2-6 boxes standing apart", 2, 6},
    {"stacked-boxes", "Table II family: 2-6 boxes, at least one resting on another", 2, 6},
    {"occluded", "Table II family: 2-6 objects, at least one partly hidden behind a taller one", 2, 6},
    {"cylinders", "Table II family: 2-5 cylinders, standing and lying", 2, 5},
    {"mixed", "Table II family: 3-7 boxes, cylinders, spheres, bowls and cups", 3, 7},
    {"complex", "Table II family: 8-14 objects of every kind, stacked and occluding", 8, 14},
    {"sequence", "one box sliding across a static scene of 3 objects (for temporal smoothing)", 4, 4},
    {"pick-and-place", "60 frames: two objects lifted away one at a time, one carried and put down elsewhere, one "
                       "sliding behind a tall box, the camera swaying slightly (for tracking)", 3, 5},
};

// Uniform numbers from a 64-bit generator, identical on every standard library.
struct Rng {
  std::mt19937_64 engine;
  explicit Rng(std::uint64_t seed) : engine(seed) {}
  double uniform(double lo, double hi) { return lo + (hi - lo) * static_cast<double>(engine() >> 11) * (1.0 / 9007199254740992.0); }
  int integer(int lo, int hi) { return lo + static_cast<int>(engine() % static_cast<std::uint64_t>(hi - lo + 1)); }
  bool chance(double p) { return uniform(0, 1) < p; }
};

// The footprint of an object on the plane it rests on: a rectangle (yawed) or a circle.
struct Footprint {
  Vector2d centre = Vector2d::Zero();
  double yaw = 0;
  Vector2d half = Vector2d::Zero();  // rectangle half extents
  double radius = 0;                 // > 0: a circle
  bool round() const { return radius > 0; }
  std::array<Vector2d, 4> corners() const {
    const Vector2d ax(std::cos(yaw), std::sin(yaw)), ay(-std::sin(yaw), std::cos(yaw));
    return {centre + half.x() * ax + half.y() * ay, centre - half.x() * ax + half.y() * ay,
            centre - half.x() * ax - half.y() * ay, centre + half.x() * ax - half.y() * ay};
  }
  // A point in the rectangle's own frame.
  Vector2d local(const Vector2d& p) const {
    const Vector2d d = p - centre;
    return {std::cos(yaw) * d.x() + std::sin(yaw) * d.y(), -std::sin(yaw) * d.x() + std::cos(yaw) * d.y()};
  }
};

double rect_point_distance(const Footprint& r, const Vector2d& p) {
  const Vector2d l = r.local(p);
  const double dx = std::max(std::abs(l.x()) - r.half.x(), 0.0), dy = std::max(std::abs(l.y()) - r.half.y(), 0.0);
  return std::hypot(dx, dy);
}

// Separating-axis test of two rectangles grown by `gap`.
bool rects_overlap(const Footprint& a, const Footprint& b, double gap) {
  for (const Footprint* f : {&a, &b}) {
    for (double angle : {f->yaw, f->yaw + M_PI / 2}) {
      const Vector2d axis(std::cos(angle), std::sin(angle));
      double lo[2] = {1e9, 1e9}, hi[2] = {-1e9, -1e9};
      int k = 0;
      for (const Footprint* g : {&a, &b}) {
        for (const auto& c : g->corners()) {
          lo[k] = std::min(lo[k], axis.dot(c));
          hi[k] = std::max(hi[k], axis.dot(c));
        }
        ++k;
      }
      if (hi[0] + gap <= lo[1] || hi[1] + gap <= lo[0]) return false;
    }
  }
  return true;
}

bool overlap(const Footprint& a, const Footprint& b, double gap) {
  if (a.round() && b.round()) return (a.centre - b.centre).norm() < a.radius + b.radius + gap;
  if (a.round()) return rect_point_distance(b, a.centre) < a.radius + gap;
  if (b.round()) return rect_point_distance(a, b.centre) < b.radius + gap;
  return rects_overlap(a, b, gap);
}

// Whether `inner` lies within the rectangle `outer`.
bool inside(const Footprint& outer, const Footprint& inner) {
  auto in = [&](const Vector2d& p, double shrink) {
    const Vector2d l = outer.local(p);
    return std::abs(l.x()) <= outer.half.x() - shrink && std::abs(l.y()) <= outer.half.y() - shrink;
  };
  if (outer.round()) return false;
  if (inner.round()) return in(inner.centre, inner.radius);
  for (const auto& c : inner.corners())
    if (!in(c, 0)) return false;
  return true;
}

// One object while a scene is built.
struct Item {
  Shape shape;
  ObjectInfo info;
  Footprint footprint;
  double base = 0, top = 0;  // z of the bottom and top [m]
  bool flat_top = false;     // a box: others may rest on it
  int support = -1;          // index of the item it rests on, -1 = table
  bool gone = false;         // taken out of the scene (pick-and-place); keeps its id slot
};

cv::Vec3b random_colour(Rng& rng) {
  // Saturated, well-lit colours so the shaded colour image separates objects.
  const double h = rng.uniform(0, 6);
  const int k = static_cast<int>(h) % 6;
  const double f = h - std::floor(h);
  const double hi = 230, lo = rng.uniform(40, 110), mid = lo + (hi - lo) * f, dim = hi - (hi - lo) * f;
  const double rgb[6][3] = {{hi, mid, lo}, {dim, hi, lo}, {lo, hi, mid}, {lo, dim, hi}, {mid, lo, hi}, {hi, lo, dim}};
  return cv::Vec3b(cv::saturate_cast<uchar>(rgb[k][2]), cv::saturate_cast<uchar>(rgb[k][1]), cv::saturate_cast<uchar>(rgb[k][0]));
}

enum class Kind { Box, Book, Standing, Lying, Sphere, Bowl, Cup };

// A box's size in all the places an Item keeps it: full extents (x, y, z) [m].
void size_box(Item& box, const Vector3d& full) {
  box.shape.size = full / 2;
  box.info.size = full;
  box.footprint.half = full.head<2>() / 2;
  box.top = full.z();
}

// A randomly sized object of `kind`, not yet placed (footprint centred at the origin).
Item make_item(Kind kind, Rng& rng) {
  Item it;
  Shape& s = it.shape;
  s.color = random_colour(rng);
  switch (kind) {
    case Kind::Box:
    case Kind::Book: {
      const Vector3d full = kind == Kind::Box
          ? Vector3d(rng.uniform(0.05, 0.2), rng.uniform(0.05, 0.16), rng.uniform(0.04, 0.16))
          : Vector3d(rng.uniform(0.16, 0.26), rng.uniform(0.11, 0.18), rng.uniform(0.02, 0.045));
      s.type = ShapeType::Box;
      size_box(it, full);
      it.info.type = kind == Kind::Box ? "box" : "book";
      it.flat_top = true;
      break;
    }
    case Kind::Standing: {
      const double r = rng.uniform(0.025, 0.055), h = rng.uniform(0.06, 0.2);
      s.type = ShapeType::Cylinder;
      s.size = {r, r, h / 2};
      it.info.type = "cylinder";
      it.info.size = {2 * r, 2 * r, h};
      it.footprint.radius = r;
      it.top = h;
      break;
    }
    case Kind::Lying: {
      const double r = rng.uniform(0.025, 0.05), len = rng.uniform(0.1, 0.22);
      s.type = ShapeType::Cylinder;
      s.size = {r, r, len / 2};
      it.info.type = "cylinder";
      it.info.size = {len, 2 * r, 2 * r};  // object frame: axis along x
      it.footprint.half = {len / 2, r};
      it.top = 2 * r;
      break;
    }
    case Kind::Sphere: {
      const double r = rng.uniform(0.03, 0.075);
      s.type = ShapeType::Sphere;
      s.size = {r, r, r};
      it.info.type = "sphere";
      it.info.size = {2 * r, 2 * r, 2 * r};
      it.footprint.radius = r;
      it.top = 2 * r;
      break;
    }
    case Kind::Bowl: {
      const double r = rng.uniform(0.06, 0.1), h = r * rng.uniform(0.5, 0.8);
      s.type = ShapeType::Bowl;
      s.size = {r, r, h / 2};
      s.wall = rng.uniform(0.004, 0.007);
      it.info.type = "bowl";
      it.info.size = {2 * r, 2 * r, h};
      it.footprint.radius = r;
      it.top = h;
      break;
    }
    case Kind::Cup: {
      const double r = rng.uniform(0.035, 0.05), h = rng.uniform(0.08, 0.12);
      s.type = ShapeType::Cup;
      s.size = {r, r, h / 2};
      s.wall = rng.uniform(0.004, 0.006);
      it.info.type = "cup";
      it.info.size = {2 * r, 2 * r, h};
      it.footprint.radius = r;
      it.top = h;
      break;
    }
  }
  return it;
}

// Puts `it` at (xy, yaw) on a surface at height `base`, and sets its pose.
void put(Item& it, const Vector2d& xy, double yaw, double base) {
  const double height = it.top - it.base;
  it.base = base;
  it.top = base + height;
  it.footprint.centre = xy;
  it.footprint.yaw = yaw;
  const Vector3d centre(xy.x(), xy.y(), base + height / 2);
  Eigen::Isometry3d object = Eigen::Translation3d(centre) * Eigen::AngleAxisd(yaw, Vector3d::UnitZ());
  it.info.pose = object;
  // Lying cylinders: the shape's axis (z) lies along the object's x.
  it.shape.pose = it.info.type == "cylinder" && it.footprint.radius == 0
                      ? object * Eigen::AngleAxisd(M_PI / 2, Vector3d::UnitY())
                      : object;
}

// Where objects go: a square region on the table, and the camera's horizontal direction.
struct Layout {
  Vector2d centre = Vector2d::Zero();
  double half = 0.2;                   // region half size [m]
  Vector2d toward_camera = -Vector2d::UnitY();  // unit, in the table plane
  Vector2d across = Vector2d::UnitX();           // unit, left to right in the image
  Vector2d table_half = Vector2d(0.6, 0.4);
  Vector3d eye = Vector3d(0, -0.6, 0.7);         // camera position
};

// Tries to place `it` on the table at a random free spot (or at `xy` when given); bounded attempts.
// `gap`: clearance to the objects on the table [m]; -1 skips the check (touching boxes placed by construction).
bool place_on_table(Item it, std::vector<Item>& items, const Layout& lay, Rng& rng, double gap,
                    const std::optional<Vector2d>& xy = std::nullopt, std::optional<double> yaw = std::nullopt) {
  for (int attempt = 0; attempt < (xy ? 1 : 80); ++attempt) {
    const Vector2d p = xy ? *xy : lay.centre + Vector2d(rng.uniform(-lay.half, lay.half), rng.uniform(-lay.half, lay.half));
    const double a = yaw ? *yaw : rng.uniform(-M_PI, M_PI);
    put(it, p, a, 0);
    // Keep the object on the table top.
    bool ok = true;
    const double reach = it.footprint.round() ? it.footprint.radius : it.footprint.half.norm();
    if (std::abs(p.x()) + reach > lay.table_half.x() - 0.01 || std::abs(p.y()) + reach > lay.table_half.y() - 0.01) ok = false;
    for (const Item& o : items)
      if (ok && o.support < 0 && overlap(o.footprint, it.footprint, gap)) ok = false;
    if (!ok) continue;
    it.support = -1;
    items.push_back(it);
    return true;
  }
  return false;
}

// Tries to rest `it` on the flat top of a randomly chosen item (the top of a stack), fully within it.
bool place_on_top(Item it, std::vector<Item>& items, Rng& rng) {
  std::vector<int> tops;
  for (size_t i = 0; i < items.size(); ++i) {
    bool covered = false;
    for (const Item& o : items) covered = covered || o.support == static_cast<int>(i);
    if (items[i].flat_top && !covered) tops.push_back(static_cast<int>(i));
  }
  if (tops.empty()) return false;
  for (int attempt = 0; attempt < 60; ++attempt) {
    const int b = tops[static_cast<size_t>(rng.integer(0, static_cast<int>(tops.size()) - 1))];
    const Item& base = items[static_cast<size_t>(b)];
    if (base.top > 0.3) continue;  // keep stacks low enough for the camera
    const Vector2d p = base.footprint.centre + Vector2d(rng.uniform(-0.5, 0.5) * base.footprint.half.x(), rng.uniform(-0.5, 0.5) * base.footprint.half.y());
    put(it, p, rng.uniform(-M_PI, M_PI), base.top);
    if (!inside(base.footprint, it.footprint)) continue;
    it.support = b;
    items.push_back(it);
    return true;
  }
  return false;
}

// A narrow box standing in front of `behind` (toward the camera), tall enough that the line of sight
// over its top meets `behind` at `cover` times its height: it splits `behind` in the image.
bool place_occluder(std::vector<Item>& items, int behind, const Layout& lay, Rng& rng, double cover = 1.0) {
  const Item& back = items[static_cast<size_t>(behind)];
  Item occ = make_item(Kind::Box, rng);
  const double w = rng.uniform(0.035, 0.06);
  const double depth = back.footprint.round() ? back.footprint.radius : back.footprint.half.norm();
  for (int attempt = 0; attempt < 10; ++attempt) {
    const double d = depth + w * 0.75 + rng.uniform(0.01, 0.04);
    // Similar triangles from the eye over the occluder's top down to the height cover * top at `behind`.
    // Aim at the far side of `behind`, so that its top face is hidden too.
    const double eye_height = lay.eye.z(), reach = (lay.eye.head<2>() - back.footprint.centre).norm() + depth;
    const double aim = cover * back.top, run = d + depth;
    const double h = std::clamp((aim * (reach - run) + eye_height * run) / std::max(reach, 1e-3), back.top * 1.1, 0.45);
    size_box(occ, {w, w, h});
    occ.base = 0;
    const Vector2d xy = back.footprint.centre + d * lay.toward_camera + rng.uniform(-0.02, 0.02) * lay.across;
    const double yaw = std::atan2(lay.across.y(), lay.across.x()) + rng.uniform(-0.3, 0.3);
    if (place_on_table(occ, items, lay, rng, 0.005, xy, yaw)) return true;
  }
  return false;
}

Kind random_kind(Rng& rng, bool with_open) {
  const Kind all[] = {Kind::Box, Kind::Box, Kind::Standing, Kind::Lying, Kind::Sphere, Kind::Bowl, Kind::Cup};
  const int n = with_open ? 7 : 5;
  return all[rng.integer(0, n - 1)];
}

// A small object for pick-and-place: any kind but lying cylinders and bowls, no wider than 9 cm.
Item small_item(Kind kind, Rng& rng) {
  Item it = make_item(kind, rng);
  const double reach = it.footprint.round() ? it.footprint.radius : it.footprint.half.norm();
  if (reach > 0.045) {  // scale the footprint down, keep the height
    const double f = 0.045 / reach;
    it.shape.size.x() *= f;
    it.shape.size.y() *= f;
    it.info.size.x() *= f;
    it.info.size.y() *= f;
    it.footprint.half *= f;
    it.footprint.radius *= f;
    if (it.info.type == "sphere") {  // a sphere stays round
      it.shape.size = Vector3d::Constant(it.shape.size.x());
      it.info.size = Vector3d::Constant(it.info.size.x());
      it.top = it.info.size.z();
    }
  }
  return it;
}

// Table positions of pick-and-place, in the layout's frame: along `across` and `toward_camera` [m].
Vector2d pick_spot(const Layout& lay, double across, double toward) {
  return lay.centre + across * lay.across + toward * lay.toward_camera;
}

// Items of pick-and-place (ids by index + 1): 1 a tall narrow box, 2 a box that later slides behind it,
// 3 and 5 objects lifted away, 4 an object carried to where 3 stood. Placed at frame 0 with every check;
// the places they move to are checked here too, so that every frame of a seed keeps one layout.
bool build_pick_and_place(std::vector<Item>& items, const Layout& lay, Rng& rng) {
  const double yaw_across = std::atan2(lay.across.y(), lay.across.x());
  Item tall = make_item(Kind::Box, rng);
  const double w = rng.uniform(0.045, 0.06), h = rng.uniform(0.16, 0.2);
  size_box(tall, {w, w, h});
  Item mover = make_item(Kind::Box, rng);
  const Vector3d full(rng.uniform(0.05, 0.07), rng.uniform(0.04, 0.06), rng.uniform(0.05, 0.08));
  size_box(mover, full);
  const Kind kinds[] = {Kind::Box, Kind::Standing, Kind::Sphere, Kind::Cup};
  Item first = small_item(kinds[rng.integer(0, 3)], rng), carried = small_item(rng.chance(0.5) ? Kind::Box : Kind::Standing, rng);
  Item last = small_item(kinds[rng.integer(0, 3)], rng);
  if (!place_on_table(tall, items, lay, rng, 0.01, pick_spot(lay, 0, 0.03), yaw_across) ||
      !place_on_table(mover, items, lay, rng, 0.01, pick_spot(lay, -0.2, -0.1), yaw_across) ||
      !place_on_table(first, items, lay, rng, 0.01, pick_spot(lay, -0.16, 0.15), rng.uniform(-M_PI, M_PI)) ||
      !place_on_table(carried, items, lay, rng, 0.01, pick_spot(lay, 0.16, 0.15), rng.uniform(-M_PI, M_PI)) ||
      !place_on_table(last, items, lay, rng, 0.01, pick_spot(lay, 0.12, -0.24), rng.uniform(-M_PI, M_PI)))
    return false;
  // Where the mover ends and where the carried object is put down must be free and on the table too.
  std::vector<Item> others = {items[0], items[4]};
  if (!place_on_table(items[1], others, lay, rng, 0.01, pick_spot(lay, 0.2, -0.1), yaw_across)) return false;
  others = {items[0], items[1], items[4]};
  return place_on_table(items[3], others, lay, rng, 0.01, pick_spot(lay, -0.16, 0.15), items[3].footprint.yaw);
}

// Frame `frame` of pick-and-place: moves, lifts and removes items (no random numbers: every frame of a
// seed draws the same layout). Frames past 59 keep the last state.
void animate_pick_and_place(std::vector<Item>& items, const Layout& lay, int frame) {
  const double f = std::clamp(frame, 0, 59);
  const auto ramp = [&](double from, double to) { return std::clamp((f - from) / (to - from), 0.0, 1.0); };
  const auto lift = [](Item& it, const Vector2d& xy, double height) {
    put(it, xy, it.footprint.yaw, height);
    it.info.held = height > 0;
  };
  // 3 (index 2): lifted 3 cm per frame over frames 8-10, gone from 11.
  Item& first = items[2];
  if (f >= 11) first.gone = true;
  else lift(first, first.footprint.centre, 0.03 * std::max(0.0, f - 7));
  // 4 (index 3): lifted over 14-16, carried across over 17-26 at 9 cm, lowered over 27-29 onto 3's place.
  Item& carried = items[3];
  const Vector2d from = pick_spot(lay, 0.16, 0.15), to = pick_spot(lay, -0.16, 0.15);
  const double height = 0.09 * (ramp(13, 16) - ramp(26, 29));
  lift(carried, from + ramp(16, 26) * (to - from), height);
  // 2 (index 1): slides behind the tall box over frames 34-57, 1.7 cm per frame.
  Item& mover = items[1];
  put(mover, pick_spot(lay, -0.2 + 0.4 * ramp(33, 57), -0.1), mover.footprint.yaw, 0);
  // 5 (index 4): lifted over 44-46, gone from 47.
  Item& last = items[4];
  if (f >= 47) last.gone = true;
  else lift(last, last.footprint.centre, 0.03 * std::max(0.0, f - 43));
}

// Fills `items` for the preset; returns false when the layout did not fit (the caller retries).
bool build(const std::string& preset, std::vector<Item>& items, const Layout& lay, Rng& rng, int frame) {
  const PresetInfo& info = preset_info(preset);
  const double yaw_across = std::atan2(lay.across.y(), lay.across.x());
  auto count = [&] { return rng.integer(info.min_objects, info.max_objects); };
  if (preset == "occluded-box") {
    Item box = make_item(Kind::Box, rng);
    const Vector3d full(rng.uniform(0.2, 0.3), rng.uniform(0.06, 0.1), rng.uniform(0.07, 0.13));
    size_box(box, full);
    return place_on_table(box, items, lay, rng, 0, lay.centre - 0.04 * lay.toward_camera, yaw_across + rng.uniform(-0.2, 0.2)) &&
           place_occluder(items, 0, lay, rng);
  }
  if (preset == "lying-cylinder-occluded") {
    Item cyl = make_item(Kind::Lying, rng);
    return place_on_table(cyl, items, lay, rng, 0, lay.centre - 0.04 * lay.toward_camera, yaw_across + rng.uniform(-0.2, 0.2)) &&
           place_occluder(items, 0, lay, rng);
  }
  if (preset == "cup" || preset == "bowl" || preset == "sphere")
    return place_on_table(make_item(preset == "cup" ? Kind::Cup : preset == "bowl" ? Kind::Bowl : Kind::Sphere, rng), items, lay,
                          rng, 0, lay.centre + Vector2d(rng.uniform(-0.03, 0.03), rng.uniform(-0.03, 0.03)));
  if (preset == "side-by-side-boxes") {
    Item a = make_item(Kind::Box, rng), b = make_item(Kind::Box, rng);
    const double yaw = yaw_across + rng.uniform(-0.3, 0.3);
    const Vector2d axis(std::cos(yaw), std::sin(yaw));
    const double gap = rng.uniform(0.0, 0.002);
    const Vector2d ca = lay.centre - (b.footprint.half.x() + gap / 2) * axis, cb = lay.centre + (a.footprint.half.x() + gap / 2) * axis;
    return place_on_table(a, items, lay, rng, -1, ca, yaw) && place_on_table(b, items, lay, rng, -1, cb, yaw);
  }
  if (preset == "staircase") {
    const double yaw = yaw_across + rng.uniform(-0.15, 0.15);
    const Vector2d back(-std::sin(yaw), std::cos(yaw));  // the books' own +y, away from the camera
    Item book = make_item(Kind::Book, rng);
    if (!place_on_table(book, items, lay, rng, 0, lay.centre + 0.04 * back * (lay.toward_camera.dot(back) > 0 ? 1 : -1), yaw)) return false;
    const double sign = lay.toward_camera.dot(back) > 0 ? -1 : 1;  // step away from the camera
    for (int k = 1; k < 3; ++k) {
      const Item& below = items.back();
      Item upper = make_item(Kind::Book, rng);
      upper.shape.size.head<2>() = below.shape.size.head<2>();
      upper.info.size.head<2>() = below.info.size.head<2>();
      upper.footprint.half = below.footprint.half;
      const Vector2d xy = below.footprint.centre + sign * rng.uniform(0.03, 0.05) * back;
      put(upper, xy, yaw, below.top);
      upper.support = static_cast<int>(items.size()) - 1;
      items.push_back(upper);
    }
    return true;
  }
  if (preset == "sequence") {
    // Static objects away from the strip the sliding box travels along.
    Item mover = make_item(Kind::Box, rng);
    const double reach = mover.footprint.half.norm() + 0.02;
    int placed = 0;
    for (int attempt = 0; attempt < 30 && placed < 3; ++attempt) {
      Item it = make_item(random_kind(rng, true), rng);
      std::vector<Item> trial = items;
      if (!place_on_table(it, trial, lay, rng, 0.01)) continue;
      const Footprint& f = trial.back().footprint;
      const double extent = f.round() ? f.radius : f.half.norm();
      if (std::abs((f.centre - lay.centre).dot(lay.toward_camera)) < reach + extent) continue;
      items = trial;
      ++placed;
    }
    if (placed < 3) return false;
    constexpr int kPeriod = 80;  // frames per crossing, back and forth
    const int phase = frame % (2 * kPeriod);
    const double s = (phase < kPeriod ? phase : 2 * kPeriod - phase) / static_cast<double>(kPeriod);
    const Vector2d xy = lay.centre + (-0.8 + 1.6 * s) * lay.half * lay.across;
    // Placed without checks so that every frame draws the same random numbers and keeps the camera.
    put(mover, xy, yaw_across + 0.3 * s, 0);
    items.push_back(mover);
    return true;
  }
  if (preset == "pick-and-place") return build_pick_and_place(items, lay, rng);
  // The Table II families.
  const int n = count();
  const bool stacked = preset == "stacked-boxes", complex = preset == "complex";
  for (int guard = 0; static_cast<int>(items.size()) < n && guard < 200; ++guard) {
    const int i = static_cast<int>(items.size());
    Kind kind = Kind::Box;
    if (preset == "cylinders") kind = rng.chance(0.6) ? Kind::Standing : Kind::Lying;
    else if (preset == "mixed" || complex || preset == "occluded") kind = random_kind(rng, preset != "occluded");
    Item it = make_item(kind, rng);
    if (stacked && it.shape.size.z() > 0.05) {  // low boxes so that stacks stay in view
      it.shape.size.z() *= 0.6;
      it.info.size.z() *= 0.6;
      it.top *= 0.6;
    }
    const bool want_stack = (stacked && i >= 1 && (i == 1 || rng.chance(0.5))) || (complex && i >= 2 && rng.chance(0.3));
    if (want_stack && place_on_top(it, items, rng)) continue;
    const bool want_occluder = (preset == "occluded" && i >= 1 && (i == 1 || rng.chance(0.3))) || (complex && i >= 1 && rng.chance(0.25));
    if (want_occluder && items[static_cast<size_t>(i - 1)].support < 0 && place_occluder(items, i - 1, lay, rng, rng.uniform(0.4, 1.0))) continue;
    place_on_table(it, items, lay, rng, complex ? 0.003 : 0.01);
  }
  if (static_cast<int>(items.size()) != n) return false;
  if (stacked) return std::any_of(items.begin(), items.end(), [](const Item& it) { return it.support >= 0; });
  return true;
}

// The table (top at z = 0), the floor below it, and sometimes a wall behind: all label 0.
void add_background(Scene& scene, const Layout& lay, Rng& rng) {
  Shape table;
  table.type = ShapeType::Box;
  table.size = {lay.table_half.x(), lay.table_half.y(), 0.02};
  table.pose = Eigen::Translation3d(0, 0, -0.02) * Eigen::Isometry3d::Identity();
  table.color = cv::Vec3b(110, 150, 190);  // light wood
  scene.shapes.push_back(table);
  Shape floor;
  floor.type = ShapeType::Plane;
  floor.size = {0, 0, 0};
  floor.pose = Eigen::Translation3d(0, 0, -0.74) * Eigen::Isometry3d::Identity();
  floor.color = cv::Vec3b(120, 120, 120);
  scene.shapes.push_back(floor);
  if (rng.chance(0.5)) {
    // A wall facing the camera beyond the table's far edge.
    const Vector2d away = -lay.toward_camera;
    const Vector2d pos = away * (std::abs(away.x()) * lay.table_half.x() + std::abs(away.y()) * lay.table_half.y() + rng.uniform(0.0, 0.4));
    Shape wall;
    wall.type = ShapeType::Plane;
    wall.size = {3, 2, 0};
    const Vector3d normal(lay.toward_camera.x(), lay.toward_camera.y(), 0);
    wall.pose = Eigen::Translation3d(pos.x(), pos.y(), 0.5) * Eigen::Quaterniond::FromTwoVectors(Vector3d::UnitZ(), normal);
    wall.color = cv::Vec3b(215, 220, 225);
    scene.shapes.push_back(wall);
  }
}

}  // namespace

const std::vector<PresetInfo>& presets() { return kPresets; }

const PresetInfo& preset_info(const std::string& name) {
  for (const auto& p : kPresets)
    if (p.name == name) return p;
  std::string names;
  for (const auto& p : kPresets) names += (names.empty() ? "" : ", ") + p.name;
  throw Error("--preset " + name + ": unknown preset (" + names + ")");
}

GeneratedScene generate_scene(const std::string& preset, std::uint64_t seed, int frame, const Camera& camera) {
  const PresetInfo& info = preset_info(preset);
  const bool pick = preset == "pick-and-place";
  const bool sequence = preset == "sequence" || pick;
  Rng rng(mix_seed(seed, sequence ? 0x5e9 : static_cast<std::uint64_t>(frame)));
  GeneratedScene out;
  out.family = info.name;
  // Bounded retries: each attempt draws a new camera and layout; the last one is kept regardless.
  std::vector<Item> items;
  Layout lay;
  for (int attempt = 0; attempt < 40; ++attempt) {
    items.clear();
    // Occlusion presets need room between camera and scene for the occluder (Kinect sees nothing below 0.5 m).
    const bool occlusion = preset == "occluded-box" || preset == "lying-cylinder-occluded";
    const double distance = rng.uniform(occlusion || pick ? 0.8 : 0.5, pick ? 1.2 : 1.5), elevation = rng.uniform(30, 70) * kDeg, azimuth = rng.uniform(-35, 35) * kDeg;
    lay.toward_camera = Vector2d(std::sin(azimuth), -std::cos(azimuth));
    lay.across = Vector2d(std::cos(azimuth), std::sin(azimuth));
    lay.table_half = Vector2d(rng.uniform(0.45, 0.8), rng.uniform(0.35, 0.6));
    lay.half = std::min(0.3 * distance * (info.max_objects > 6 ? 1.0 : 0.8), 0.3);
    lay.centre = Vector2d(rng.uniform(-1, 1) * std::max(lay.table_half.x() - lay.half - 0.1, 0.0),
                          rng.uniform(-1, 1) * std::max(lay.table_half.y() - lay.half - 0.1, 0.0));
    const Vector3d target(lay.centre.x(), lay.centre.y(), 0.03);
    out.eye = target + distance * Vector3d(lay.toward_camera.x() * std::cos(elevation), lay.toward_camera.y() * std::cos(elevation), std::sin(elevation));
    out.target = target;
    lay.eye = out.eye;
    out.world_to_camera = look_at(out.eye, out.target);
    if (!build(preset, items, lay, rng, pick ? 0 : frame)) continue;
    // Every object's centre in the image.
    bool ok = true;
    for (const Item& it : items) {
      if (preset == "sequence" && &it == &items.back()) continue;  // the sliding box stays within the region
      const Vector3d c = out.world_to_camera * it.info.pose.translation();
      const double u = camera.cx + camera.fx * c.x() / c.z(), v = camera.cy + camera.fy * c.y() / c.z();
      if (c.z() <= 0.2 || u < 0.05 * camera.width || u > 0.95 * camera.width || v < 0.05 * camera.height || v > 0.95 * camera.height) ok = false;
      // At least 0.5 m from the camera (the Kinect's minimum range), so no object is lost entirely.
      if ((out.eye - it.info.pose.translation()).norm() < bounding_radius(it.shape) + 0.5) ok = false;
    }
    if (ok) break;
  }
  Rng background_rng(mix_seed(seed, sequence ? 0xb9 : 0xb9 + 0x100000000ULL * static_cast<std::uint64_t>(frame)));
  add_background(out.scene, lay, background_rng);
  if (pick) {
    animate_pick_and_place(items, lay, frame);
    // The camera sways by up to 1.5 cm sideways and 1 cm up and down (at most 2.2 mm per frame).
    const double f = std::clamp(frame, 0, 59);
    const Vector3d across(lay.across.x(), lay.across.y(), 0);
    out.eye += 0.015 * std::sin(2 * M_PI * f / 60) * across + 0.01 * std::sin(2 * M_PI * f / 40) * Vector3d::UnitZ();
    out.world_to_camera = look_at(out.eye, out.target);
  }
  for (size_t i = 0; i < items.size(); ++i) {
    Item& it = items[i];
    if (it.gone) continue;  // its id is not given to another object
    it.shape.label = static_cast<int>(i) + 1;
    it.info.id = static_cast<int>(i) + 1;
    it.info.shape = static_cast<int>(out.scene.shapes.size());
    out.scene.shapes.push_back(it.shape);
    out.objects.push_back(it.info);
  }
  return out;
}

}  // namespace clutterseg::synth
