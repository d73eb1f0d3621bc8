// The ROS wiring of one clutterseg::Segmenter, shared by the node (node_main.cpp) and the nodelet.
//
// Subscribes to depth/image + depth/camera_info (image_transport camera subscriber, queue 1). The callback
// only checks the frame and leaves it in a one-frame mailbox; a worker thread segments the newest frame
// and publishes. A frame still in the mailbox when a newer one arrives is dropped and counted, so the
// driver is never blocked. Every frame that is not dropped is segmented in arrival order by one stateful
// Segmenter: the same stream as `clutterseg segment DIR` on the same frames.
#pragma once

#include <clutterseg/segmenter.hpp>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <diagnostic_updater/diagnostic_updater.h>
#include <image_transport/image_transport.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

namespace clutterseg_ros {

class SegmentationNode {
 public:
  // Reads the parameters of pnh's namespace; throws clutterseg::Error (naming the parameter) when the
  // segmenter refuses one. nh: input topics; pnh: parameters and outputs.
  SegmentationNode(ros::NodeHandle nh, ros::NodeHandle pnh);
  ~SegmentationNode();  // stops the worker after its current frame
  SegmentationNode(const SegmentationNode&) = delete;
  SegmentationNode& operator=(const SegmentationNode&) = delete;

 private:
  struct Frame {
    sensor_msgs::ImageConstPtr image;
    sensor_msgs::CameraInfoConstPtr info;
    ros::WallTime arrived;
  };

  void on_depth(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info);
  void work();
  void process(const Frame& frame);
  // Camera frame -> ~target_frame at the frame's stamp; identity (and camera frame id) without one.
  Eigen::Isometry3d objects_transform(const std_msgs::Header& image_header, std_msgs::Header& objects_header);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);
  // Logs `message` as an error; another one with the same `key` only after 5 s (a broken stream
  // arrives 30 times a second). The key leaves out what varies from frame to frame (stamps, times).
  void log_throttled(const std::string& key, const std::string& message);

  ros::NodeHandle nh_, pnh_;
  clutterseg::Params params_;
  clutterseg::Segmenter segmenter_;
  std::string input_topic_;  // the depth image topic after remapping, for log lines (any thread)
  std::string target_frame_;
  double tf_timeout_s_ = 0.05;

  image_transport::ImageTransport it_, private_it_;
  image_transport::CameraSubscriber depth_sub_;
  image_transport::CameraPublisher labels_pub_;
  ros::Publisher cloud_pub_, markers_pub_, objects_pub_, plane_pub_, stats_pub_, params_pub_;
  struct DebugImage {
    std::string name;
    image_transport::Publisher pub;
  };
  std::vector<DebugImage> debug_pubs_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  diagnostic_updater::Updater diagnostics_;
  ros::WallTimer diagnostics_timer_;

  // Mailbox between the subscriber callback and the worker.
  std::mutex mutex_;
  std::condition_variable wake_;
  std::optional<Frame> pending_;
  bool stopping_ = false;
  std::thread worker_;

  // Counters (totals since start) and the recent latencies for /diagnostics.
  std::atomic<uint64_t> received_{0}, processed_{0}, dropped_{0}, rejected_{0}, failed_{0};
  std::mutex recent_mutex_;
  std::deque<double> recent_latency_ms_, recent_segment_ms_;
  std::optional<ros::Time> last_stamp_;  // worker only

  struct Logged {
    ros::WallTime when;
    int suppressed = 0;
  };
  std::mutex log_mutex_;
  std::map<std::string, Logged> logged_;  // by key; a few kinds of problem in practice
};

}  // namespace clutterseg_ros
