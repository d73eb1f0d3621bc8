#include "clutterseg/synth/scene.hpp"

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

// Infinite cylinder of radius r about z, limited to |z| <= h; inside = hit from within (inner wall).
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

}  // namespace

bool intersect(const Shape& s, const Vector3d& origin, const Vector3d& dir, double& t, Vector3d& normal) {
  // Work in the shape frame, where every shape is centred and axis-aligned.
  const Eigen::Isometry3d inv = s.pose.inverse();
  const Vector3d o = inv * origin, d = inv.linear() * dir;
  Hit hit;
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
  }
  if (!hit.valid()) return false;
  t = hit.t;
  normal = s.pose.linear() * hit.n;
  return true;
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
  const Eigen::Isometry3d cam_to_world = world_to_camera.inverse();
  const Vector3d eye = cam_to_world.translation();
  parallel_for_rows(camera.height, [&](int begin, int end) {
    for (int v = begin; v < end; ++v)
      for (int u = 0; u < camera.width; ++u) {
        const Vector3d ray_cam((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
        const Vector3d dir = (cam_to_world.linear() * ray_cam).normalized();
        double best = max_range;
        int label = -1;
        Vector3d normal;
        for (const auto& s : scene.shapes) {
          double t;
          Vector3d n;
          if (intersect(s, eye, dir, t, n) && t < best) { best = t; label = s.label; normal = n; }
        }
        if (label < 0) continue;
        const Vector3d p_cam = world_to_camera * (eye + best * dir);
        Vector3d n_cam = world_to_camera.linear() * normal;
        if (n_cam.dot(p_cam) > 0) n_cam = -n_cam;
        out.depth.at<float>(v, u) = static_cast<float>(p_cam.z());
        out.labels.at<int>(v, u) = label;
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
