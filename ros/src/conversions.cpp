#include "conversions.hpp"

#include <clutterseg/config.hpp>
#include <clutterseg/debug.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <nlohmann/json.hpp>
#include <set>

namespace clutterseg_ros {

namespace {

// ~target_frame, ~tf_timeout: the node's own; ~image_transport, ~diagnostic_period: read by
// image_transport and diagnostic_updater from the same private namespace.
const std::set<std::string> kNodeSettings = {"target_frame", "tf_timeout", "image_transport", "diagnostic_period"};

// "/clutterseg" + "graph.theta_c" -> "/clutterseg/graph/theta_c"
std::string ros_name(const std::string& ns, std::string dotted) {
  std::replace(dotted.begin(), dotted.end(), '.', '/');
  return (ns.empty() || ns.back() != '/' ? ns + "/" : ns) + dotted;
}

nlohmann::json to_json(const XmlRpc::XmlRpcValue& v, const std::string& ns, const std::string& path) {
  using XmlRpc::XmlRpcValue;
  switch (v.getType()) {
    case XmlRpcValue::TypeBoolean: return static_cast<const bool&>(v);
    case XmlRpcValue::TypeInt: return static_cast<const int&>(v);
    case XmlRpcValue::TypeDouble: return static_cast<const double&>(v);
    case XmlRpcValue::TypeString: return static_cast<const std::string&>(v);
    case XmlRpcValue::TypeArray: {
      nlohmann::json a = nlohmann::json::array();
      for (int i = 0; i < v.size(); ++i) a.push_back(to_json(v[i], ns, path + "." + std::to_string(i)));
      return a;
    }
    case XmlRpcValue::TypeStruct: {
      nlohmann::json o = nlohmann::json::object();
      for (const auto& [key, value] : v) o[key] = to_json(value, ns, path.empty() ? key : path + "." + key);
      return o;
    }
    default:
      throw clutterseg::Error("ROS parameter " + ros_name(ns, path) +
                              ": must be a bool, number, string or dictionary (see clutterseg --dump-config)");
  }
}

}  // namespace

bool is_node_setting(const std::string& name) { return kNodeSettings.count(name) > 0; }

clutterseg::Params params_from_ros(const XmlRpc::XmlRpcValue& private_params, const std::string& ns) {
  nlohmann::json given = nlohmann::json::object();
  if (private_params.getType() == XmlRpc::XmlRpcValue::TypeStruct)
    for (const auto& [key, value] : private_params)
      if (!is_node_setting(key)) given[key] = to_json(value, ns, key);
  try {
    return clutterseg::params_from_json(given.dump(), "ROS parameters in " + ns);
  } catch (const clutterseg::Error& e) {
    // The core names a parameter as in --dump-config ('graph.theta_c'); add the name a ROS user sets.
    std::string message = e.what();
    const std::string marker = "parameter '";
    if (const size_t begin = message.find(marker); begin != std::string::npos) {
      const size_t name_begin = begin + marker.size();
      if (const size_t end = message.find('\'', name_begin); end != std::string::npos)
        message += " (ROS parameter " + ros_name(ns, message.substr(name_begin, end - name_begin)) + ")";
    }
    throw clutterseg::Error(message);
  }
}

std::optional<double> depth_unit_m(const std::string& encoding) {
  if (encoding == "16UC1" || encoding == "mono16") return 0.001;
  if (encoding == "32FC1") return 1.0;
  return std::nullopt;
}

std::optional<std::string> check_depth_frame(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info) {
  const auto unit = depth_unit_m(image.encoding);
  if (!unit)
    return "encoding '" + image.encoding + "', expected 16UC1 (mm) or 32FC1 (m)";
  const size_t bytes_per_pixel = image.encoding == "32FC1" ? 4 : 2;
  if (image.width == 0 || image.height == 0) return std::string("image is empty");
  if (image.step < image.width * bytes_per_pixel || image.data.size() < size_t{image.step} * image.height)
    return "image data (" + std::to_string(image.data.size()) + " bytes, step " + std::to_string(image.step) +
           ") is too small for " + std::to_string(image.width) + "x" + std::to_string(image.height);
  if (image.is_bigendian) return std::string("big-endian depth is not supported");
  if (info.width != image.width || info.height != image.height)
    return "image is " + std::to_string(image.width) + "x" + std::to_string(image.height) + " but its CameraInfo is " +
           std::to_string(info.width) + "x" + std::to_string(info.height);
  if (!(info.K[0] > 0 && info.K[4] > 0)) return std::string("CameraInfo has no focal length (K[0], K[4] must be > 0)");
  return std::nullopt;
}

clutterseg::Camera camera_from_info(const sensor_msgs::CameraInfo& info, double unit) {
  clutterseg::Camera camera;
  camera.fx = info.K[0];
  camera.fy = info.K[4];
  camera.cx = info.K[2];
  camera.cy = info.K[5];
  camera.width = static_cast<int>(info.width);
  camera.height = static_cast<int>(info.height);
  camera.depth_unit_m = unit;
  return camera;
}

std::vector<int> view_ids(const cv::Mat& object_labels, const cv::Mat& view) {
  double max_id = 0;
  cv::minMaxLoc(object_labels, nullptr, &max_id);
  std::vector<int> id(static_cast<size_t>(max_id) + 1, 0);
  for (int y = 0; y < object_labels.rows; ++y) {
    const int* from = object_labels.ptr<int>(y);
    const int* to = view.ptr<int>(y);
    for (int x = 0; x < object_labels.cols; ++x)
      if (from[x] > 0) id[static_cast<size_t>(from[x])] = to[x];
  }
  return id;
}

namespace {

geometry_msgs::Point to_point(const Eigen::Vector3d& p) {
  geometry_msgs::Point m;
  m.x = p.x();
  m.y = p.y();
  m.z = p.z();
  return m;
}

// The box's pose in `to`: the axes as a right-handed rotation (PCA may give a reflection).
geometry_msgs::Pose box_pose(const clutterseg::OrientedBox& box, const Eigen::Isometry3d& to) {
  Eigen::Matrix3d axes = box.axes.cast<double>();
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
  const Eigen::Quaterniond q(to.linear() * axes);
  geometry_msgs::Pose pose;
  pose.position = to_point(to * box.center.cast<double>());
  pose.orientation.x = q.x();
  pose.orientation.y = q.y();
  pose.orientation.z = q.z();
  pose.orientation.w = q.w();
  return pose;
}

// The debug overlay's colour of each label id (BGR from render_labels), as RGB in [0, 1].
std::vector<std::array<float, 3>> label_colours(int max_id) {
  cv::Mat ids(1, max_id + 1, CV_32S);
  for (int i = 0; i <= max_id; ++i) ids.at<int>(0, i) = i;
  const cv::Mat bgr = clutterseg::render_labels(ids);
  std::vector<std::array<float, 3>> rgb(static_cast<size_t>(max_id) + 1);
  for (int i = 0; i <= max_id; ++i) {
    const cv::Vec3b c = bgr.at<cv::Vec3b>(0, i);
    rgb[static_cast<size_t>(i)] = {c[2] / 255.f, c[1] / 255.f, c[0] / 255.f};
  }
  return rgb;
}

}  // namespace

ObjectArray objects_message(const clutterseg::Result& r, const std::vector<int>& view_id,
                            const Eigen::Isometry3d& camera_to_frame, const std_msgs::Header& header) {
  ObjectArray msg;
  msg.header = header;
  for (const clutterseg::Object& o : r.objects) {
    const int id = o.id > 0 && o.id < static_cast<int>(view_id.size()) ? view_id[static_cast<size_t>(o.id)] : 0;
    if (id <= 0) continue;
    Object m;
    m.id = static_cast<uint32_t>(id);
    m.pixel_count = static_cast<uint32_t>(o.pixel_count);
    m.centroid = to_point(camera_to_frame * o.centroid.cast<double>());
    m.box = box_pose(o.box, camera_to_frame);
    m.box_size.x = o.box.extents.x();
    m.box_size.y = o.box.extents.y();
    m.box_size.z = o.box.extents.z();
    m.confidence = o.cut_cost;
    m.support = o.support;
    m.background = o.background;
    m.age = static_cast<uint32_t>(o.age);
    m.frames_missed = static_cast<uint32_t>(o.frames_missed);
    m.split_from = static_cast<uint32_t>(o.split_from);
    m.merged_with.assign(o.merged_with.begin(), o.merged_with.end());
    msg.objects.push_back(m);
  }
  std::sort(msg.objects.begin(), msg.objects.end(), [](const Object& a, const Object& b) { return a.id < b.id; });
  msg.has_support_plane = r.support_plane.has_value();
  if (r.support_plane) {
    // n.x + d = 0 in the camera frame; with x = R^T (y - t): (R n).y + d - (R n).t = 0.
    const Eigen::Vector3d n = camera_to_frame.linear() * r.support_plane->normal.cast<double>();
    const double d = r.support_plane->offset - n.dot(camera_to_frame.translation());
    msg.support_plane = {n.x(), n.y(), n.z(), d};
  }
  return msg;
}

geometry_msgs::Pose plane_pose(const clutterseg::Result& r, const Eigen::Isometry3d& camera_to_frame) {
  geometry_msgs::Pose pose;
  if (!r.support_plane) return pose;
  const Eigen::Vector3d n = r.support_plane->normal.cast<double>();
  const double d = r.support_plane->offset;
  Eigen::Vector3d above = Eigen::Vector3d::Zero();  // the camera
  for (const auto& o : r.objects)
    if (o.support) above = o.centroid.cast<double>();
  const Eigen::Vector3d origin = above - n * (n.dot(above) + d);
  const Eigen::Quaterniond q(camera_to_frame.linear() * Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), n));
  pose.position = to_point(camera_to_frame * origin);
  pose.orientation.x = q.x();
  pose.orientation.y = q.y();
  pose.orientation.z = q.z();
  pose.orientation.w = q.w();
  return pose;
}

visualization_msgs::MarkerArray markers_message(const ObjectArray& objects, const clutterseg::Result& r,
                                                const Eigen::Isometry3d& camera_to_frame) {
  visualization_msgs::MarkerArray markers;
  visualization_msgs::Marker clear;
  clear.header = objects.header;
  clear.action = visualization_msgs::Marker::DELETEALL;
  markers.markers.push_back(clear);

  uint32_t max_id = 0;
  for (const auto& o : objects.objects) max_id = std::max(max_id, o.id);
  const auto colours = label_colours(static_cast<int>(max_id));
  auto cube = [&](const std::string& ns, int id, const geometry_msgs::Pose& pose, const geometry_msgs::Vector3& size) {
    visualization_msgs::Marker m;
    m.header = objects.header;
    m.ns = ns;
    m.id = id;
    m.type = visualization_msgs::Marker::CUBE;
    m.action = visualization_msgs::Marker::ADD;
    m.pose = pose;
    m.scale.x = std::max(size.x, 0.002);  // RViz hides zero-size cubes; flat objects stay visible
    m.scale.y = std::max(size.y, 0.002);
    m.scale.z = std::max(size.z, 0.002);
    m.color.a = 0.5f;
    return m;
  };
  bool table_listed = false;
  for (const auto& o : objects.objects) {
    visualization_msgs::Marker box = cube("objects", static_cast<int>(o.id), o.box, o.box_size);
    const auto& c = colours[o.id];
    box.color.r = c[0];
    box.color.g = c[1];
    box.color.b = c[2];
    markers.markers.push_back(box);
    visualization_msgs::Marker text = box;
    text.ns = "ids";
    text.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
    text.text = std::to_string(o.id);
    text.pose.orientation = geometry_msgs::Quaternion();
    text.pose.orientation.w = 1;
    text.scale.x = text.scale.y = 0;
    text.scale.z = 0.03;
    text.color.r = text.color.g = text.color.b = text.color.a = 1.f;
    markers.markers.push_back(text);
    table_listed = table_listed || o.support;
  }
  if (!table_listed)
    for (const auto& o : r.objects)
      if (o.support) {
        geometry_msgs::Vector3 size;
        size.x = o.box.extents.x();
        size.y = o.box.extents.y();
        size.z = o.box.extents.z();
        visualization_msgs::Marker table = cube("support", 0, box_pose(o.box, camera_to_frame), size);
        table.color.r = table.color.g = table.color.b = 0.6f;
        table.color.a = 0.3f;
        markers.markers.push_back(table);
        break;
      }
  return markers;
}

sensor_msgs::PointCloud2 cloud_message(const cv::Mat& points, const cv::Mat& view, const std_msgs::Header& header) {
  sensor_msgs::PointCloud2 cloud;
  cloud.header = header;
  cloud.height = static_cast<uint32_t>(points.rows);
  cloud.width = static_cast<uint32_t>(points.cols);
  auto field = [](const char* name, uint32_t offset, uint8_t type) {
    sensor_msgs::PointField f;
    f.name = name;
    f.offset = offset;
    f.datatype = type;
    f.count = 1;
    return f;
  };
  cloud.fields = {field("x", 0, sensor_msgs::PointField::FLOAT32), field("y", 4, sensor_msgs::PointField::FLOAT32),
                  field("z", 8, sensor_msgs::PointField::FLOAT32), field("label", 12, sensor_msgs::PointField::UINT32)};
  cloud.is_bigendian = false;
  cloud.point_step = 16;
  cloud.row_step = cloud.point_step * cloud.width;
  cloud.is_dense = false;
  cloud.data.resize(size_t{cloud.row_step} * cloud.height);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  uint8_t* out = cloud.data.data();
  for (int y = 0; y < points.rows; ++y) {
    const cv::Vec3f* p = points.ptr<cv::Vec3f>(y);
    const int* label = view.ptr<int>(y);
    for (int x = 0; x < points.cols; ++x, out += 16) {
      const bool valid = clutterseg::valid_point(p[x]);
      const float xyz[3] = {valid ? p[x][0] : nan, valid ? p[x][1] : nan, valid ? p[x][2] : nan};
      const uint32_t id = static_cast<uint32_t>(std::max(label[x], 0));
      std::memcpy(out, xyz, 12);
      std::memcpy(out + 12, &id, 4);
    }
  }
  return cloud;
}

}  // namespace clutterseg_ros
