// The clutterseg nodelet: the SegmentationNode inside a nodelet manager (e.g. the camera driver's, so
// depth images reach it without serialisation).
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include <memory>

#include "segmentation_node.hpp"

namespace clutterseg_ros {

class SegmentationNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      node_ = std::make_unique<SegmentationNode>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const clutterseg::Error& e) {
      NODELET_FATAL("%s", e.what());
      throw;  // the manager reports the nodelet as not loaded
    }
  }
  std::unique_ptr<SegmentationNode> node_;
};

}  // namespace clutterseg_ros

PLUGINLIB_EXPORT_CLASS(clutterseg_ros::SegmentationNodelet, nodelet::Nodelet)
