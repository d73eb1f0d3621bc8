#include "segmentation_node.hpp"

#include <clutterseg/config.hpp>
#include <clutterseg/debug.hpp>
#include <clutterseg/io.hpp>
#include <clutterseg/objects.hpp>

#include <algorithm>
#include <functional>
#include <utility>

#include <clutterseg_ros/FrameStatistics.h>
#include <clutterseg_ros/ObjectArray.h>
#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/PoseStamped.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/String.h>
#include <visualization_msgs/MarkerArray.h>

#include "conversions.hpp"

namespace clutterseg_ros {

namespace {

clutterseg::Params read_params(const ros::NodeHandle& pnh) {
  XmlRpc::XmlRpcValue all;  // stays invalid (= no parameters, all defaults) when the namespace is empty
  ros::param::get(pnh.getNamespace(), all);
  return params_from_ros(all, pnh.getNamespace());
}

double milliseconds(const ros::WallDuration& d) { return d.toSec() * 1e3; }

// q-quantile of a copy of the values (nearest rank).
double quantile(std::deque<double> values, double q) {
  if (values.empty()) return 0;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * static_cast<double>(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

constexpr size_t kRecentFrames = 300;  // window of /diagnostics' latency figures (10 s at 30 Hz)

}  // namespace

SegmentationNode::SegmentationNode(ros::NodeHandle nh, ros::NodeHandle pnh)
    : nh_(nh),
      pnh_(pnh),
      params_(read_params(pnh)),
      segmenter_(params_),
      it_(nh),
      private_it_(pnh),
      diagnostics_(nh, pnh, pnh.getNamespace()) {
  pnh_.param<std::string>("target_frame", target_frame_, "");
  pnh_.param("tf_timeout", tf_timeout_s_, 0.05);
  if (!target_frame_.empty()) {
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh_);
  }

  labels_pub_ = private_it_.advertiseCamera("labels", 5);
  objects_pub_ = pnh_.advertise<ObjectArray>("objects", 5);
  markers_pub_ = pnh_.advertise<visualization_msgs::MarkerArray>("markers", 1);
  plane_pub_ = pnh_.advertise<geometry_msgs::PoseStamped>("support_plane", 5);
  cloud_pub_ = pnh_.advertise<sensor_msgs::PointCloud2>("cloud", 1);
  stats_pub_ = pnh_.advertise<FrameStatistics>("statistics", 10);
  params_pub_ = pnh_.advertise<std_msgs::String>("params", 1, /*latch=*/true);
  for (const char* name : {"depth", "normals", "edge_value", "edges", "patches", "objects", "graph"})
    debug_pubs_.push_back({name, private_it_.advertise(std::string("debug/") + name, 1)});

  std_msgs::String effective;
  effective.data = clutterseg::params_to_json(params_);
  params_pub_.publish(effective);

  diagnostics_.setHardwareID("none");
  diagnostics_.add("segmentation", this, &SegmentationNode::diagnose);
  diagnostics_timer_ = pnh_.createWallTimer(ros::WallDuration(0.25), [this](const ros::WallTimerEvent&) { diagnostics_.update(); });

  worker_ = std::thread([this] { work(); });
  input_topic_ = nh_.resolveName("depth/image");  // before subscribing: a nodelet's callbacks start at once
  depth_sub_ = it_.subscribeCamera("depth/image", 1, &SegmentationNode::on_depth, this,
                                   image_transport::TransportHints("raw", ros::TransportHints(), pnh_));
  ROS_INFO("%s: segmenting %s (objects_only %s, target frame '%s')", pnh_.getNamespace().c_str(),
           input_topic_.c_str(), params_.support.objects_only ? "on" : "off", target_frame_.c_str());
}

SegmentationNode::~SegmentationNode() {
  depth_sub_.shutdown();
  diagnostics_timer_.stop();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (worker_.joinable()) worker_.join();
}

void SegmentationNode::on_depth(const sensor_msgs::ImageConstPtr& image, const sensor_msgs::CameraInfoConstPtr& info) {
  const ros::WallTime arrived = ros::WallTime::now();
  ++received_;
  // Refused here, so a malformed frame never displaces a good one waiting for the worker.
  if (const auto problem = check_depth_frame(*image, *info)) {
    ++rejected_;
    log_throttled(*problem, "depth image on " + input_topic_ + ": " + *problem + "; frame skipped");
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (pending_) ++dropped_;  // the worker is still busy: the older waiting frame gives way
    pending_ = Frame{image, info, arrived};
  }
  wake_.notify_one();
}

void SegmentationNode::work() {
  for (;;) {
    Frame frame;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || pending_.has_value(); });
      if (stopping_) return;
      frame = std::move(*pending_);
      pending_.reset();
    }
    const std::string what = "depth image on " + input_topic_;
    try {
      process(frame);
    } catch (const clutterseg::Error& e) {  // the library refused the frame; the node goes on
      ++failed_;
      log_throttled(e.what(), what + ": " + e.what());
    } catch (const std::exception& e) {
      ++failed_;
      log_throttled(e.what(), what + ": unexpected error: " + e.what());
    }
  }
}

void SegmentationNode::process(const Frame& frame) {
  const ros::WallTime start = ros::WallTime::now();
  const std_msgs::Header& header = frame.image->header;
  if (last_stamp_ && header.stamp < *last_stamp_) {  // a bag started again, or the driver restarted
    ROS_WARN("%s: time went backwards on %s; temporal smoothing and object ids start again", pnh_.getNamespace().c_str(),
             input_topic_.c_str());
    segmenter_.reset();
  }
  last_stamp_ = header.stamp;

  const clutterseg::Camera camera = camera_from_info(*frame.info, *depth_unit_m(frame.image->encoding));
  const cv_bridge::CvImageConstPtr depth = cv_bridge::toCvShare(frame.image);  // no copy
  const clutterseg::Result r = segmenter_.segment(depth->image, camera);
  const ros::WallTime segmented = ros::WallTime::now();

  // The label image `clutterseg segment` writes: the objects-only view when support.objects_only is set.
  const cv::Mat view = params_.support.objects_only ? clutterseg::objects_only(r.object_labels, r.objects, params_.tracking.enabled)
                                                        : r.object_labels;
  if (labels_pub_.getNumSubscribers() > 0) {
    const cv_bridge::CvImage labels(header, "16UC1", clutterseg::labels_to_u16(view));
    labels_pub_.publish(labels.toImageMsg(), frame.info);
  }
  if (objects_pub_.getNumSubscribers() > 0 || markers_pub_.getNumSubscribers() > 0 || plane_pub_.getNumSubscribers() > 0) {
    std_msgs::Header objects_header;
    const Eigen::Isometry3d to_frame = objects_transform(header, objects_header);
    const ObjectArray objects = objects_message(r, view_ids(r.object_labels, view), to_frame, objects_header);
    if (objects_pub_.getNumSubscribers() > 0) objects_pub_.publish(objects);
    if (markers_pub_.getNumSubscribers() > 0) markers_pub_.publish(markers_message(objects, r, to_frame));
    if (r.support_plane && plane_pub_.getNumSubscribers() > 0) {
      geometry_msgs::PoseStamped plane;
      plane.header = objects_header;
      plane.pose = plane_pose(r, to_frame);
      plane_pub_.publish(plane);
    }
  }
  if (cloud_pub_.getNumSubscribers() > 0) cloud_pub_.publish(cloud_message(r.points, view, header));
  for (const DebugImage& debug : debug_pubs_) {
    if (debug.pub.getNumSubscribers() == 0) continue;
    cv::Mat image;
    if (debug.name == "depth") image = clutterseg::render_depth(r.depth);
    else if (debug.name == "normals") image = clutterseg::render_normals(r.normals);
    else if (debug.name == "edge_value") image = clutterseg::render_edge_value(r.edge_value);
    else if (debug.name == "edges") image = clutterseg::render_edges(r.edges);
    else if (debug.name == "patches") image = clutterseg::render_labels(r.core_patch_labels);
    else if (debug.name == "objects") image = clutterseg::render_overlay(view, cv::Mat(), r.depth);
    else if (debug.name == "graph") image = clutterseg::render_graph(r, camera);
    const std::string encoding = image.channels() == 1 ? "mono8" : "bgr8";
    debug.pub.publish(cv_bridge::CvImage(header, encoding, image).toImageMsg());
  }
  ++processed_;
  const ros::WallTime done = ros::WallTime::now();

  FrameStatistics stats;
  stats.header = header;
  stats.received = received_;
  stats.processed = processed_;
  stats.dropped = dropped_;
  stats.rejected = rejected_;
  stats.failed = failed_;
  stats.wait_ms = milliseconds(start - frame.arrived);
  stats.segment_ms = r.timings_ms.empty() ? 0 : r.timings_ms.back().second;
  stats.publish_ms = milliseconds(done - segmented);
  stats.latency_ms = milliseconds(done - frame.arrived);
  stats.age_ms = (ros::Time::now() - header.stamp).toSec() * 1e3;
  for (const auto& [stage, ms] : r.timings_ms) {
    stats.stage_names.push_back(stage);
    stats.stage_ms.push_back(ms);
  }
  stats_pub_.publish(stats);
  {
    std::lock_guard<std::mutex> lock(recent_mutex_);
    recent_latency_ms_.push_back(stats.latency_ms);
    recent_segment_ms_.push_back(stats.segment_ms);
    if (recent_latency_ms_.size() > kRecentFrames) {
      recent_latency_ms_.pop_front();
      recent_segment_ms_.pop_front();
    }
  }
}

Eigen::Isometry3d SegmentationNode::objects_transform(const std_msgs::Header& image_header, std_msgs::Header& objects_header) {
  objects_header = image_header;
  if (target_frame_.empty() || target_frame_ == image_header.frame_id) return Eigen::Isometry3d::Identity();
  try {
    const geometry_msgs::TransformStamped t =
        tf_buffer_->lookupTransform(target_frame_, image_header.frame_id, image_header.stamp, ros::Duration(tf_timeout_s_));
    objects_header.frame_id = target_frame_;
    const auto& q = t.transform.rotation;
    const auto& p = t.transform.translation;
    Eigen::Isometry3d to = Eigen::Isometry3d::Identity();
    to.linear() = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized().toRotationMatrix();
    to.translation() = Eigen::Vector3d(p.x, p.y, p.z);
    return to;
  } catch (const tf2::TransformException& e) {
    const std::string frames = "no transform from '" + image_header.frame_id + "' to '" + target_frame_ + "'";
    log_throttled(frames, frames + "; objects published in '" + image_header.frame_id + "' (" + e.what() + ")");
    return Eigen::Isometry3d::Identity();
  }
}

void SegmentationNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::deque<double> latency, segment;
  {
    std::lock_guard<std::mutex> lock(recent_mutex_);
    latency = recent_latency_ms_;
    segment = recent_segment_ms_;
  }
  const uint64_t dropped = dropped_, rejected = rejected_, failed = failed_;
  if (rejected + failed > 0)
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR, "frames refused (see the log)");
  else if (dropped > 0)
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "frames dropped: input faster than segmentation");
  else
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "segmenting");
  status.add("received", static_cast<uint64_t>(received_));
  status.add("processed", static_cast<uint64_t>(processed_));
  status.add("dropped", dropped);
  status.add("rejected", rejected);
  status.add("failed", failed);
  status.add("latency median [ms]", quantile(latency, 0.5));
  status.add("latency p95 [ms]", quantile(latency, 0.95));
  status.add("segmentation median [ms]", quantile(segment, 0.5));
  status.add("recent frames", latency.size());
}

void SegmentationNode::log_throttled(const std::string& key, const std::string& message) {
  std::lock_guard<std::mutex> lock(log_mutex_);
  const ros::WallTime now = ros::WallTime::now();
  if (const auto it = logged_.find(key); it != logged_.end() && (now - it->second.when).toSec() < 5.0) {
    ++it->second.suppressed;
    return;
  }
  if (logged_.size() > 64) logged_.clear();  // bounded, whatever the messages
  Logged& entry = logged_[key];
  const std::string repeats =
      entry.suppressed > 0 ? " (" + std::to_string(entry.suppressed) + " more since the last report)" : "";
  ROS_ERROR("%s: %s%s", pnh_.getNamespace().c_str(), message.c_str(), repeats.c_str());
  entry = {now, 0};
}

}  // namespace clutterseg_ros
