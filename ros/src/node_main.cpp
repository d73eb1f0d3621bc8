// The clutterseg ROS node: the SegmentationNode in a process of its own.
#include <ros/ros.h>

#include "segmentation_node.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "clutterseg");
  ros::NodeHandle nh, pnh("~");
  try {
    clutterseg_ros::SegmentationNode node(nh, pnh);
    ros::spin();  // the subscriber callback only hands frames to the node's worker thread
  } catch (const clutterseg::Error& e) {
    ROS_FATAL("%s", e.what());
    return 1;
  }
  return 0;
}
