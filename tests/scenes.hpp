// Small analytic scenes for the stage tests, rendered exactly (no noise) by synth::render.
// The camera looks down at the table (z = 0) from about 0.9 m at 50 degrees; labels: 0 = table.
#pragma once

#include "clutterseg/synth/scene.hpp"

namespace clutterseg::scenes {

using synth::Shape;
using synth::ShapeType;

struct TestScene {
  synth::Scene scene;
  Camera camera = synth::default_camera(320, 240);
  Eigen::Isometry3d world_to_camera = synth::look_at({0, -0.6, 0.7}, {0, 0, 0});
  synth::Rendering render() const { return synth::render(scene, camera, world_to_camera); }
};

inline Shape table(double half = 0.8) {
  Shape s;
  s.type = ShapeType::Plane;
  s.size = {half, half, 0};
  s.label = 0;
  return s;
}

inline Shape box(int label, Eigen::Vector3d centre, Eigen::Vector3d half, double yaw = 0) {
  Shape s;
  s.type = ShapeType::Box;
  s.pose = Eigen::Translation3d(centre) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
  s.size = half;
  s.label = label;
  return s;
}

// A cylinder lying on the table along the world x axis (or `yaw` from it).
inline Shape lying_cylinder(int label, Eigen::Vector3d centre, double radius, double half_length, double yaw = 0) {
  Shape s;
  s.type = ShapeType::Cylinder;
  s.pose = Eigen::Translation3d(centre) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
           Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY());
  s.size = {radius, radius, half_length};
  s.label = label;
  return s;
}

inline Shape standing(ShapeType type, int label, Eigen::Vector3d base, double radius, double height) {
  Shape s;
  s.type = type;
  s.pose = Eigen::Translation3d(base + Eigen::Vector3d(0, 0, height / 2)) * Eigen::AngleAxisd(0, Eigen::Vector3d::UnitZ());
  s.size = {radius, radius, height / 2};
  s.label = label;
  return s;
}

inline TestScene plane_scene() { return {{{table()}}}; }

inline TestScene box_on_plane() { return {{{table(), box(1, {0, 0, 0.05}, {0.08, 0.06, 0.05}, 0.4)}}}; }

// A box split in two by a thinner, taller box standing in front of it (paper Fig. 5).
inline TestScene occluded_box() {
  return {{{table(), box(1, {0, 0.08, 0.06}, {0.15, 0.05, 0.06}), box(2, {0, -0.08, 0.09}, {0.025, 0.025, 0.09})}}};
}

inline TestScene cup() { return {{{table(), standing(ShapeType::Cup, 1, {0, 0, 0}, 0.045, 0.1)}}}; }

// A cylinder lying across the view, cut in two by a box standing in front of it (paper Fig. 6).
inline TestScene lying_cylinder_occluded() {
  return {{{table(), lying_cylinder(1, {0, 0.05, 0.04}, 0.04, 0.16), box(2, {0, -0.07, 0.1}, {0.025, 0.025, 0.1})}}};
}

inline TestScene stacked_boxes() {
  return {{{table(), box(1, {0, 0, 0.04}, {0.1, 0.08, 0.04}), box(2, {0.01, 0.0, 0.11}, {0.06, 0.05, 0.03}, 0.3)}}};
}

inline TestScene side_by_side_boxes() {
  return {{{table(), box(1, {-0.06, 0, 0.05}, {0.06, 0.05, 0.05}), box(2, {0.06, 0, 0.05}, {0.06, 0.05, 0.05})}}};
}

// Two books lying flat, the upper one shifted back: a staircase of aligned surfaces.
inline TestScene staircase() {
  return {{{table(), box(1, {0, 0, 0.015}, {0.1, 0.07, 0.015}), box(2, {0, 0.04, 0.045}, {0.1, 0.07, 0.015})}}};
}

// Two boxes side by side, 2 cm apart, of different heights (so that no face of one continues a face
// of the other).
inline TestScene two_boxes_apart() {
  return {{{table(), box(1, {-0.07, 0, 0.05}, {0.06, 0.05, 0.05}), box(2, {0.07, 0, 0.035}, {0.06, 0.05, 0.035})}}};
}

// A box on a table in front of a wall (a vertical plane 25 cm behind it, 60 cm high).
inline TestScene box_before_wall() {
  Shape wall;
  wall.type = ShapeType::Plane;
  wall.pose = Eigen::Translation3d(0, 0.25, 0.3) * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX());
  wall.size = {0.8, 0.3, 0};
  wall.label = 0;
  TestScene s{{{table(0.25), wall, box(1, {0, 0, 0.05}, {0.08, 0.06, 0.05}, 0.4)}}};
  s.world_to_camera = synth::look_at({0, -0.7, 0.6}, {0, 0.05, 0.1});
  return s;
}

// An open laptop's lid: a thin upright board, 40 x 25 cm, standing on a table that shows behind it.
// As flat, as upright and as long as box_before_wall()'s wall, but it stands on the table and hides it.
inline TestScene board_on_table() {
  TestScene s{{{table(), box(1, {0, 0, 0.125}, {0.2, 0.005, 0.125})}}};
  s.world_to_camera = synth::look_at({0, -0.8, 0.7}, {0, 0.05, 0.05});
  return s;
}

// Two boxes of equal height with table between them: co-planar tops separated by background
// (paper Fig. 5, red box), which must not be joined.
inline TestScene separate_boxes() {
  return {{{table(), box(1, {-0.12, 0, 0.05}, {0.06, 0.05, 0.05}), box(2, {0.12, 0, 0.05}, {0.06, 0.05, 0.05})}}};
}

// A box whose front and top faces are each cut in two by a tall thin box in front of it: the camera
// sees over occluded_box()'s occluder, this one hides the full height of the face.
inline TestScene occluded_box_split() {
  return {{{table(), box(1, {0, 0.08, 0.06}, {0.15, 0.05, 0.06}), box(2, {0, -0.08, 0.15}, {0.025, 0.025, 0.15})}}};
}

// A bowl (a spherical shell cut at its rim) standing on the table: rim at `height`, wall `wall` thick.
inline Shape bowl(int label, Eigen::Vector3d base, double radius, double height, double wall = 0.005) {
  Shape s;
  s.type = ShapeType::Bowl;
  s.pose = Eigen::Translation3d(base + Eigen::Vector3d(0, 0, height / 2)) * Eigen::Isometry3d::Identity();
  s.size = {radius, radius, height / 2};
  s.wall = wall;
  s.label = label;
  return s;
}

// Two lying cylinders on one axis with bare table between them: aligned, similar, but not occluded.
inline TestScene coaxial_cylinders() {
  return {{{table(), lying_cylinder(1, {-0.11, 0.05, 0.04}, 0.04, 0.07), lying_cylinder(2, {0.11, 0.05, 0.04}, 0.04, 0.07)}}};
}

// The lying cylinder cut by an occluder, with a standing cylinder and a sphere beside it (paper Fig. 6).
inline TestScene curved_objects() {
  return {{{table(), lying_cylinder(1, {0, 0.05, 0.04}, 0.04, 0.16), box(2, {0, -0.07, 0.1}, {0.025, 0.025, 0.1}),
            standing(ShapeType::Cylinder, 3, {-0.2, -0.12, 0}, 0.035, 0.16),
            standing(ShapeType::Sphere, 4, {0.2, -0.12, 0}, 0.05, 0.1)}}};
}

}  // namespace clutterseg::scenes
