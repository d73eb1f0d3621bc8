// Random table-top scenes for `clutterseg synth`: the paper's hard cases and the six scene families of
// its Table II, each object resting on the table or on another object without interpenetration.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "clutterseg/synth/scene.hpp"

namespace clutterseg::synth {

struct PresetInfo {
  std::string name;         // --preset NAME
  std::string description;
  int min_objects = 1, max_objects = 1;  // every frame holds this many objects
};

// All presets, in the order `clutterseg synth --list` prints them.
const std::vector<PresetInfo>& presets();
// Throws Error("--preset NAME: unknown preset (...)") for an unknown name.
const PresetInfo& preset_info(const std::string& name);

struct ObjectInfo {
  int id = 0;                 // label in the label image (1..n; pick-and-place: ids of removed objects are skipped)
  std::string type;           // box, book, cylinder, sphere, bowl, cup
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // full extents along the object's own x, y, z [m]
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  // object frame (its bounding-box centre) -> world
  int shape = 0;              // index into GeneratedScene::scene.shapes
  bool held = false;          // lifted or carried (pick-and-place): in the air, not resting
};

struct GeneratedScene {
  std::string family;         // what eval groups by: the preset name (boxes, complex, cup, ...)
  Scene scene;                // table (top at z = 0), floor, maybe a wall (label 0), then the objects
  std::vector<ObjectInfo> objects;
  Eigen::Vector3d eye = Eigen::Vector3d::Zero(), target = Eigen::Vector3d::Zero();  // camera placement, world
  Eigen::Isometry3d world_to_camera = Eigen::Isometry3d::Identity();
};

// Frame `frame` of a preset: a function of (preset, seed, frame) only. `sequence` keeps the scene and
// camera of frame 0 and moves one object a little every frame; `pick-and-place` keeps the scene of frame 0
// and lifts, carries and slides objects (an object keeps its id in every frame; a removed one's id is
// never given to another).
GeneratedScene generate_scene(const std::string& preset, std::uint64_t seed, int frame, const Camera& camera);

}  // namespace clutterseg::synth
