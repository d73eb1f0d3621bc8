// Analytic scenes and exact ray casting: the ground truth behind `clutterseg synth` and the tests.
// World frame: the table top is z = 0, z up, metres.
#pragma once

#include <vector>

#include "clutterseg/types.hpp"

namespace clutterseg::synth {

enum class ShapeType { Plane, Box, Cylinder, Sphere, Cup };

struct Shape {
  ShapeType type = ShapeType::Box;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // shape frame -> world
  // Plane: half extents x, y of a rectangle in the shape's xy plane (0 = unbounded), normal +z.
  // Box: half extents. Cylinder/Cup: radius, radius, half height along the shape's z (Cup: open at
  // +z, with a bottom). Sphere: radius in x.
  Eigen::Vector3d size = Eigen::Vector3d::Ones();
  double wall = 0.005;  // Cup wall and bottom thickness [m]
  int label = 0;        // instance id written to the label image (0 = table/background)
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

// A 640x480 (or scaled) Kinect-like camera: fx = fy = 525 * width / 640.
Camera default_camera(int width = 640, int height = 480);

}  // namespace clutterseg::synth
