// The clutterseg ROS node: the SegmentationNode in a process of its own.
#include <ros/ros.h>

#include <csignal>

#include "segmentation_node.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "clutterseg");
  // SIGTERM (docker stop, systemd, a test stopping it by PID) shuts down as cleanly as roscpp's SIGINT.
  std::signal(SIGTERM, [](int) { ros::requestShutdown(); });
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
