#include "clutterseg/synth/scene.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "clutterseg/parallel.hpp"

namespace clutterseg::synth {

namespace {

using Eigen::Vector3d;

// Keeps the nearest positive hit.
struct Hit {
  double t = std::numeric_limits<double>::infinity();
  Vector3d n = Vector3d::Zero();
  void offer(double t_new, const Vector3d& n_new) {
    if (t_new > 1e-9 && t_new < t) { t = t_new; n = n_new; }
  }
  bool valid() const { return std::isfinite(t); }
};

void hit_plane(const Vector3d& o, const Vector3d& d, const Vector3d& half, Hit& hit) {
  if (std::abs(d.z()) < 1e-12) return;
  const double t = -o.z() / d.z();
  const Vector3d p = o + t * d;
  if ((half.x() > 0 && std::abs(p.x()) > half.x()) || (half.y() > 0 && std::abs(p.y()) > half.y())) return;
  hit.offer(t, Vector3d::UnitZ());
}

void hit_box(const Vector3d& o, const Vector3d& d, const Vector3d& half, Hit& hit) {
  double t_near = -std::numeric_limits<double>::infinity(), t_far = std::numeric_limits<double>::infinity();
  int axis = -1;
  double sign = 1;
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-12) {
      if (std::abs(o[a]) > half[a]) return;
      continue;
    }
    double t0 = (-half[a] - o[a]) / d[a], t1 = (half[a] - o[a]) / d[a];
    double s = -1;
    if (t0 > t1) { std::swap(t0, t1); s = 1; }
    if (t0 > t_near) { t_near = t0; axis = a; sign = s; }
    t_far = std::min(t_far, t1);
  }
  if (axis < 0 || t_near > t_far || t_near <= 0) return;
  Vector3d n = Vector3d::Zero();
  n[axis] = sign;
  hit.offer(t_near, n);
}

// Infinite cylinder of radius r about z, limited to zlo <= z <= zhi; inner = seen from within (inner wall).
void hit_tube(const Vector3d& o, const Vector3d& d, double r, double zlo, double zhi, bool inner, Hit& hit) {
  const double a = d.x() * d.x() + d.y() * d.y();
  if (a < 1e-12) return;
  const double b = 2 * (o.x() * d.x() + o.y() * d.y());
  const double c = o.x() * o.x() + o.y() * o.y() - r * r;
  const double disc = b * b - 4 * a * c;
  if (disc < 0) return;
  const double sq = std::sqrt(disc);
  for (double t : {(-b - sq) / (2 * a), (-b + sq) / (2 * a)}) {
    const Vector3d p = o + t * d;
    if (p.z() < zlo || p.z() > zhi) continue;
    Vector3d n(p.x(), p.y(), 0);
    n.normalize();
    if (inner) n = -n;
    // Only the side that faces the ray is visible.
    if (n.dot(d) < 0) hit.offer(t, n);
  }
}

void hit_disc(const Vector3d& o, const Vector3d& d, double z, double r_in, double r_out, const Vector3d& n, Hit& hit) {
  if (std::abs(d.z()) < 1e-12) return;
  const double t = (z - o.z()) / d.z();
  const Vector3d p = o + t * d;
  const double rr = p.x() * p.x() + p.y() * p.y();
  if (rr > r_out * r_out || rr < r_in * r_in) return;
  if (n.dot(d) < 0) hit.offer(t, n);
}

void hit_sphere(const Vector3d& o, const Vector3d& d, double r, Hit& hit) {
  const double b = o.dot(d), c = o.squaredNorm() - r * r, disc = b * b - c;
  if (disc < 0) return;
  const double t = -b - std::sqrt(disc);
  hit.offer(t, (o + t * d).normalized());
}

// The band zlo <= z <= zhi of a sphere about the origin (d need not be unit); inner = concave side.
void hit_sphere_band(const Vector3d& o, const Vector3d& d, double r, double zlo, double zhi, bool inner, Hit& hit) {
  const double a = d.squaredNorm(), b = o.dot(d), c = o.squaredNorm() - r * r, disc = b * b - a * c;
  if (disc < 0) return;
  const double sq = std::sqrt(disc);
  for (double t : {(-b - sq) / a, (-b + sq) / a}) {
    const Vector3d p = o + t * d;
    if (p.z() < zlo || p.z() > zhi) continue;
    Vector3d n = p / r;
    if (inner) n = -n;
    if (n.dot(d) < 0) hit.offer(t, n);
  }
}

// Nearest hit in the shape frame, where every shape is centred and axis-aligned.
void intersect_local(const Shape& s, const Vector3d& o, const Vector3d& d, Hit& hit) {
  switch (s.type) {
    case ShapeType::Plane: hit_plane(o, d, s.size, hit); break;
    case ShapeType::Box: hit_box(o, d, s.size, hit); break;
    case ShapeType::Sphere: hit_sphere(o, d, s.size.x(), hit); break;
    case ShapeType::Cylinder:
      hit_tube(o, d, s.size.x(), -s.size.z(), s.size.z(), false, hit);
      hit_disc(o, d, s.size.z(), 0, s.size.x(), Vector3d::UnitZ(), hit);
      hit_disc(o, d, -s.size.z(), 0, s.size.x(), -Vector3d::UnitZ(), hit);
      break;
    case ShapeType::Cup: {
      const double r = s.size.x(), h = s.size.z(), w = s.wall;
      hit_tube(o, d, r, -h, h, false, hit);                         // outer wall (convex)
      hit_tube(o, d, r - w, -h + w, h, true, hit);                  // inner wall (concave)
      hit_disc(o, d, h, r - w, r, Vector3d::UnitZ(), hit);          // rim
      hit_disc(o, d, -h + w, 0, r - w, Vector3d::UnitZ(), hit);     // inner bottom
      hit_disc(o, d, -h, 0, r, -Vector3d::UnitZ(), hit);            // outer bottom
      break;
    }
    case ShapeType::Bowl: {
      // Frame with the sphere centre at the origin: rim at z = 0, foot at z = -height.
      const double r = s.size.x(), height = 2 * s.size.z(), w = s.wall, ri = r - w;
      const Vector3d oc = o - Vector3d(0, 0, s.size.z());
      Hit local;
      hit_sphere_band(oc, d, r, -height, 0, false, local);                               // outer (convex)
      hit_sphere_band(oc, d, ri, -height + w, 0, true, local);                           // inner (concave)
      hit_disc(oc, d, 0, ri, r, Vector3d::UnitZ(), local);                               // rim
      hit_disc(oc, d, -height + w, 0, std::sqrt(std::max(0.0, ri * ri - (height - w) * (height - w))),
               Vector3d::UnitZ(), local);                                                // inner floor
      hit_disc(oc, d, -height, 0, std::sqrt(std::max(0.0, r * r - height * height)), -Vector3d::UnitZ(), local);  // foot
      if (local.valid()) hit.offer(local.t, local.n);
      break;
    }
  }
}

}  // namespace

bool intersect(const Shape& s, const Vector3d& origin, const Vector3d& dir, double& t, Vector3d& normal) {
  const Eigen::Isometry3d inv = s.pose.inverse();
  Hit hit;
  intersect_local(s, inv * origin, inv.linear() * dir, hit);
  if (!hit.valid()) return false;
  t = hit.t;
  normal = s.pose.linear() * hit.n;
  return true;
}

double bounding_radius(const Shape& s) {
  switch (s.type) {
    case ShapeType::Plane:
      if (s.size.x() <= 0 || s.size.y() <= 0) return std::numeric_limits<double>::infinity();
      return std::hypot(s.size.x(), s.size.y());
    case ShapeType::Box: return s.size.norm();
    case ShapeType::Sphere: return s.size.x();
    case ShapeType::Cylinder:
    case ShapeType::Cup:
    case ShapeType::Bowl: return std::hypot(s.size.x(), s.size.z());
  }
  return std::numeric_limits<double>::infinity();
}

RayCaster::RayCaster(const Scene& scene, const Camera& camera, const Eigen::Isometry3d& scene_to_view,
                     const Vector3d& origin, int margin_px)
    : camera_(camera), origin_(origin), margin_(std::max(0, margin_px)) {
  tiles_x_ = (camera.width + 2 * margin_ + tile_ - 1) / tile_;
  tiles_y_ = (camera.height + 2 * margin_ + tile_ - 1) / tile_;
  tiles_.assign(static_cast<size_t>(tiles_x_) * tiles_y_, {});
  for (size_t i = 0; i < scene.shapes.size(); ++i) {
    const Shape& s = scene.shapes[i];
    const Eigen::Isometry3d shape_to_view = scene_to_view * s.pose;
    const Eigen::Isometry3d view_to_shape = shape_to_view.inverse();
    const double r = bounding_radius(s);
    const Vector3d c = shape_to_view.translation() - origin;
    shapes_.push_back({&s, view_to_shape.linear(), view_to_shape * origin, shape_to_view.linear(), c, r});
    // Conservative image rectangle of the bounding sphere seen from `origin`: every point of the sphere
    // has x <= c.x + r and z >= c.z - r, so its image lies within the bounds below.
    int tx0 = 0, tx1 = tiles_x_ - 1, ty0 = 0, ty1 = tiles_y_ - 1;
    if (std::isfinite(r) && c.z() - r > 1e-3) {
      auto bound = [&](double centre, double f, double pc, bool upper) {
        const double e = upper ? centre + r : centre - r;
        const bool far = upper ? e < 0 : e > 0;  // the far depth gives the extreme ratio then
        return pc + f * e / (far ? c.z() + r : c.z() - r);
      };
      const double u0 = bound(c.x(), camera.fx, camera.cx, false), u1 = bound(c.x(), camera.fx, camera.cx, true);
      const double v0 = bound(c.y(), camera.fy, camera.cy, false), v1 = bound(c.y(), camera.fy, camera.cy, true);
      auto tile_of = [&](double p) { return static_cast<int>(std::floor((p + margin_) / tile_)); };
      tx0 = std::max(0, tile_of(u0 - 1));
      tx1 = std::min(tiles_x_ - 1, tile_of(u1 + 1));
      ty0 = std::max(0, tile_of(v0 - 1));
      ty1 = std::min(tiles_y_ - 1, tile_of(v1 + 1));
    }
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) tiles_[static_cast<size_t>(ty) * tiles_x_ + tx].push_back(static_cast<int>(i));
  }
  // Nearest bounding spheres first, so that a close hit lets the far shapes be skipped.
  auto nearest = [&](int a, int b) {
    const Local &la = shapes_[static_cast<size_t>(a)], &lb = shapes_[static_cast<size_t>(b)];
    const double da = std::isfinite(la.radius) ? la.centre.norm() - la.radius : 1e300;
    const double db = std::isfinite(lb.radius) ? lb.centre.norm() - lb.radius : 1e300;
    return da < db || (da == db && a < b);
  };
  for (size_t i = 0; i < shapes_.size(); ++i) all_.push_back(static_cast<int>(i));
  std::sort(all_.begin(), all_.end(), nearest);
  for (auto& tile : tiles_) std::sort(tile.begin(), tile.end(), nearest);
}

Vector3d RayCaster::pixel_ray(double u, double v) const {
  return Vector3d((u - camera_.cx) / camera_.fx, (v - camera_.cy) / camera_.fy, 1.0).normalized();
}

bool is_convex(const Shape& s) { return s.type != ShapeType::Cup && s.type != ShapeType::Bowl; }

int RayCaster::cast(const Vector3d& dir, double u, double v, double max_t, double& t, Vector3d& normal, int ignore) const {
  const std::vector<int>* candidates = &all_;
  if (std::isfinite(u) && std::isfinite(v)) {
    const double fx = std::floor((u + margin_) / tile_), fy = std::floor((v + margin_) / tile_);
    if (fx >= 0 && fy >= 0 && fx < tiles_x_ && fy < tiles_y_)
      candidates = &tiles_[static_cast<size_t>(fy) * tiles_x_ + static_cast<size_t>(fx)];
  }
  int best = -1;
  double best_t = max_t;
  Vector3d best_n = Vector3d::Zero();
  for (int i : *candidates) {
    if (i == ignore) continue;
    const Local& l = shapes_[static_cast<size_t>(i)];
    if (std::isfinite(l.radius)) {
      // Bounding sphere: the ray misses it, or cannot reach it before the best hit so far.
      const double b = dir.dot(l.centre);
      if (b + l.radius < 0 || b - l.radius >= best_t) continue;
      if (l.centre.squaredNorm() - b * b > l.radius * l.radius) continue;
    }
    Hit hit;
    intersect_local(*l.shape, l.origin, l.to_shape * dir, hit);
    if (hit.valid() && hit.t < best_t) { best_t = hit.t; best = i; best_n = hit.n; }
  }
  if (best >= 0) {
    t = best_t;
    normal = shapes_[static_cast<size_t>(best)].to_view * best_n;
  }
  return best;
}

Eigen::Isometry3d look_at(const Vector3d& eye, const Vector3d& target) {
  const Vector3d z = (target - eye).normalized();
  Vector3d x = z.cross(Vector3d::UnitZ());
  if (x.norm() < 1e-9) x = Vector3d::UnitX();
  x.normalize();
  const Vector3d y = z.cross(x);
  Eigen::Matrix3d R;  // rows: camera axes in world coordinates
  R.row(0) = x.transpose();
  R.row(1) = y.transpose();
  R.row(2) = z.transpose();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = -R * eye;
  return T;
}

Rendering render(const Scene& scene, const Camera& camera, const Eigen::Isometry3d& world_to_camera, double max_range) {
  Rendering out;
  out.depth = cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(0));
  out.labels = cv::Mat(camera.height, camera.width, CV_32S, cv::Scalar(0));
  out.normals = cv::Mat(camera.height, camera.width, CV_32FC3, cv::Scalar::all(0));
  const RayCaster caster(scene, camera, world_to_camera);
  parallel_for_rows(camera.height, [&](int begin, int end) {
    for (int v = begin; v < end; ++v)
      for (int u = 0; u < camera.width; ++u) {
        const Vector3d dir = caster.pixel_ray(u, v);
        double t = 0;
        Vector3d n_cam;
        const int hit = caster.cast(dir, u, v, max_range, t, n_cam);
        if (hit < 0) continue;
        const Vector3d p_cam = t * dir;
        if (n_cam.dot(p_cam) > 0) n_cam = -n_cam;
        out.depth.at<float>(v, u) = static_cast<float>(p_cam.z());
        out.labels.at<int>(v, u) = scene.shapes[static_cast<size_t>(hit)].label;
        out.normals.at<cv::Vec3f>(v, u) = cv::Vec3f(float(n_cam.x()), float(n_cam.y()), float(n_cam.z()));
      }
  });
  return out;
}

Camera default_camera(int width, int height) {
  Camera c;
  c.fx = c.fy = 525.0 * width / 640.0;
  c.cx = (width - 1) / 2.0;
  c.cy = (height - 1) / 2.0;
  c.width = width;
  c.height = height;
  return c;
}

}  // namespace clutterseg::synth
