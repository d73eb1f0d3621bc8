// End-to-end latency and drop rate of a running clutterseg node (docs/ROS.md).
//
//   clutterseg_ros_latency DATASET [--node /clutterseg] [--depth /camera/depth/image_raw]
//                          [--rates 5,10,20,30,40,60] [--seconds 10]
//
// Publishes the dataset's depth frames (16UC1, in name order, cycling) with their CameraInfo at each rate,
// stamped with the wall clock when published, and subscribes to the node's labels and statistics. Per
// rate: frames sent, labelled and dropped; end-to-end latency (publish -> labels received here) and the
// library's own time per frame (Result.timings_ms "total", from ~statistics of the same frames).
#include <clutterseg/io.hpp>

#include <algorithm>
#include <cstdio>
#include <map>
#include <mutex>
#include <sstream>

#include <clutterseg_ros/FrameStatistics.h>
#include <cv_bridge/cv_bridge.h>
#include <image_transport/image_transport.h>
#include <ros/ros.h>

namespace {

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

struct Received {
  std::mutex mutex;
  std::map<ros::Time, double> latency_ms;  // per stamp: publish -> labels received here
  std::map<ros::Time, double> segment_ms;  // per stamp: the library's own time (from ~statistics)
  uint64_t dropped = 0;                    // the node's counter, latest value
};

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "clutterseg_latency", ros::init_options::AnonymousName);
  std::string dataset, node = "/clutterseg", depth_topic = "/camera/depth/image_raw", rates_arg = "5,10,20,30,40,60";
  double seconds = 10;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
      return argv[++i];
    };
    if (a == "--node") node = value();
    else if (a == "--depth") depth_topic = value();
    else if (a == "--rates") rates_arg = value();
    else if (a == "--seconds") seconds = std::stod(value());
    else dataset = a;
  }
  if (dataset.empty()) {
    std::fprintf(stderr, "usage: clutterseg_ros_latency DATASET [--node NAME] [--depth TOPIC] [--rates 5,10,30] [--seconds S]\n");
    return 2;
  }
  std::vector<double> rates;
  std::stringstream list(rates_arg);
  for (std::string r; std::getline(list, r, ',');) rates.push_back(std::stod(r));

  const clutterseg::Camera camera = clutterseg::read_camera_json(std::filesystem::path(dataset) / "camera.json");
  std::vector<sensor_msgs::Image> frames;
  for (const auto& f : clutterseg::list_dataset(dataset)) {
    cv::Mat depth = clutterseg::read_depth_png(f.depth);
    std_msgs::Header header;
    header.frame_id = "camera_depth_optical_frame";
    frames.push_back(*cv_bridge::CvImage(header, "16UC1", depth).toImageMsg());
  }
  sensor_msgs::CameraInfo info;
  info.width = static_cast<uint32_t>(camera.width);
  info.height = static_cast<uint32_t>(camera.height);
  info.K = {camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1};
  info.header.frame_id = "camera_depth_optical_frame";

  ros::NodeHandle nh;
  image_transport::ImageTransport it(nh);
  image_transport::CameraPublisher pub = it.advertiseCamera(depth_topic, 1);
  Received got;
  image_transport::Subscriber labels = it.subscribe(node + "/labels", 100, [&](const sensor_msgs::ImageConstPtr& m) {
    const double ms = (ros::Time::now() - m->header.stamp).toSec() * 1e3;
    std::lock_guard<std::mutex> lock(got.mutex);
    got.latency_ms[m->header.stamp] = ms;
  });
  ros::Subscriber stats = nh.subscribe<clutterseg_ros::FrameStatistics>(
      node + "/statistics", 100, [&](const clutterseg_ros::FrameStatisticsConstPtr& s) {
        std::lock_guard<std::mutex> lock(got.mutex);
        got.segment_ms[s->header.stamp] = s->segment_ms;
        got.dropped = std::max<uint64_t>(got.dropped, s->dropped);
      });
  ros::AsyncSpinner spinner(1);
  spinner.start();

  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(20);
  while (ros::ok() && (pub.getNumSubscribers() == 0 || labels.getNumPublishers() == 0 || stats.getNumPublishers() == 0)) {
    if (ros::WallTime::now() > give_up) {
      std::fprintf(stderr, "clutterseg_ros_latency: no node %s subscribed to %s within 20 s\n", node.c_str(), depth_topic.c_str());
      return 1;
    }
    ros::WallDuration(0.05).sleep();
  }

  std::printf("| input rate [Hz] | sent | labelled | dropped | end-to-end median [ms] | p95 [ms] | library median [ms] | p95 [ms] | "
              "ROS overhead median [ms] | p95 [ms] |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  size_t next = 0;
  for (const double rate : rates) {
    uint64_t dropped_before;
    {
      std::lock_guard<std::mutex> lock(got.mutex);
      got.latency_ms.clear();
      got.segment_ms.clear();
      dropped_before = got.dropped;
    }
    const int count = std::max(1, static_cast<int>(rate * seconds));
    ros::WallRate pace(rate);
    for (int i = 0; i < count && ros::ok(); ++i, ++next) {
      auto image = boost::make_shared<sensor_msgs::Image>(frames[next % frames.size()]);
      auto frame_info = boost::make_shared<sensor_msgs::CameraInfo>(info);
      image->header.seq = frame_info->header.seq = static_cast<uint32_t>(next);
      image->header.stamp = frame_info->header.stamp = ros::Time::now();
      pub.publish(image, frame_info);
      pace.sleep();
    }
    ros::WallDuration(1.0).sleep();  // the last frames' labels
    std::lock_guard<std::mutex> lock(got.mutex);
    // Per labelled frame: end-to-end, the library's part of it, and the rest (transport, conversion,
    // waiting for the worker, publishing).
    std::vector<double> end_to_end, library, overhead;
    for (const auto& [stamp, ms] : got.latency_ms) {
      const auto seg = got.segment_ms.find(stamp);
      if (seg == got.segment_ms.end()) continue;
      end_to_end.push_back(ms);
      library.push_back(seg->second);
      overhead.push_back(ms - seg->second);
    }
    std::printf("| %g | %d | %zu | %llu | %.1f | %.1f | %.1f | %.1f | %.1f | %.1f |\n", rate, count, got.latency_ms.size(),
                static_cast<unsigned long long>(got.dropped - dropped_before), quantile(end_to_end, 0.5),
                quantile(end_to_end, 0.95), quantile(library, 0.5), quantile(library, 0.95), quantile(overhead, 0.5),
                quantile(overhead, 0.95));
    std::fflush(stdout);
  }
  spinner.stop();
  return 0;
}
