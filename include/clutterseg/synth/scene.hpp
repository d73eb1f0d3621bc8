// Analytic scenes and exact ray casting: the ground truth behind `clutterseg synth` and the tests.
// World frame: the table top is z = 0, z up, metres.
#pragma once

#include <vector>

#include "clutterseg/types.hpp"

namespace clutterseg::synth {

enum class ShapeType { Plane, Box, Cylinder, Sphere, Cup, Bowl };

struct Shape {
  ShapeType type = ShapeType::Box;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // shape frame -> world
  // Plane: half extents x, y of a rectangle in the shape's xy plane (0 = unbounded), normal +z.
  // Box: half extents. Cylinder/Cup: radius, radius, half height along the shape's z (Cup: open at
  // +z, with a bottom). Sphere: radius in x. Bowl: rim radius, rim radius, half height; a spherical
  // shell (sphere of the rim radius, centred on the rim at z = +half height), open at +z and cut flat
  // at z = -half height (its foot); the height (2 x half height) must be below the rim radius.
  Eigen::Vector3d size = Eigen::Vector3d::Ones();
  double wall = 0.005;  // Cup and Bowl wall and bottom thickness [m]
  int label = 0;        // instance id written to the label image (0 = table/background)
  cv::Vec3b color{180, 180, 180};  // BGR albedo for the shaded colour image
};

struct Scene {
  std::vector<Shape> shapes;
};

// Camera at `eye` looking at `target` with world z up in the image; returns world -> camera
// (camera frame: x right, y down, z forward).
Eigen::Isometry3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);

struct Rendering {
  cv::Mat depth;   // CV_32F metres (camera z), 0 = nothing hit
  cv::Mat labels;  // CV_32S shape label of the nearest hit
  cv::Mat normals; // CV_32FC3 camera-frame surface normal facing the camera, 0 = none
};

// Exact ray casting of every pixel centre; the nearest hit wins.
Rendering render(const Scene& scene, const Camera& camera, const Eigen::Isometry3d& world_to_camera,
                 double max_range = 10.0);

// Nearest ray hit with one shape: distance t > 0 along the unit direction, and the outward normal.
bool intersect(const Shape& shape, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double& t,
               Eigen::Vector3d& normal);

// Radius of a sphere about the shape's origin that holds the whole shape (+inf for an unbounded plane).
double bounding_radius(const Shape& shape);

// Plane, Box, Cylinder, Sphere: a surface point facing a viewpoint is never hidden from it by its own shape.
bool is_convex(const Shape& shape);

// Nearest hit of many rays from one viewpoint with a scene: shapes are moved into the viewpoint's frame
// once, and each ray only tests the shapes whose projected bounding sphere covers its image tile.
class RayCaster {
 public:
  // `scene_to_view`: scene frame -> view frame (camera: x right, y down, z forward); rays start at
  // `origin` (view frame). `camera` gives the image in which tiles are laid out; `margin_px` extends
  // the tiled area beyond the image (rays outside it test every shape).
  RayCaster(const Scene& scene, const Camera& camera, const Eigen::Isometry3d& scene_to_view,
            const Eigen::Vector3d& origin = Eigen::Vector3d::Zero(), int margin_px = 0);
  // Nearest hit with t in (0, max_t) along the unit direction `dir` (view frame) whose image point
  // is (u, v) as seen from `origin`; returns the shape index or -1. Shape `ignore` is not tested.
  int cast(const Eigen::Vector3d& dir, double u, double v, double max_t, double& t, Eigen::Vector3d& normal,
           int ignore = -1) const;
  // The ray through pixel (u, v) of the camera image, from `origin` (unit, view frame).
  Eigen::Vector3d pixel_ray(double u, double v) const;
  const Camera& camera() const { return camera_; }

 private:
  struct Local {  // a shape with the view -> shape transform precomputed
    const Shape* shape;
    Eigen::Matrix3d to_shape;     // rotation view -> shape
    Eigen::Vector3d origin;       // ray origin in the shape frame
    Eigen::Matrix3d to_view;      // rotation shape -> view (for normals)
    Eigen::Vector3d centre;       // bounding sphere centre relative to the ray origin (view frame)
    double radius;                // bounding sphere radius (+inf: unbounded)
  };
  std::vector<Local> shapes_;
  Camera camera_;
  Eigen::Vector3d origin_;
  int margin_ = 0, tile_ = 8, tiles_x_ = 0, tiles_y_ = 0;
  std::vector<std::vector<int>> tiles_;  // shape indices per tile
  std::vector<int> all_;
};

// A 640x480 (or scaled) Kinect-like camera: fx = fy = 525 * width / 640.
Camera default_camera(int width = 640, int height = 480);

}  // namespace clutterseg::synth
