// Pure conversions between ROS messages/parameters and the library's types. No node handle, no master:
// unit-tested alone (ros/tests/test_ros_conversions.cpp).
#pragma once

#include <clutterseg/params.hpp>
#include <clutterseg/segmenter.hpp>
#include <clutterseg/types.hpp>

#include <Eigen/Geometry>
#include <optional>
#include <string>

#include <clutterseg_ros/ObjectArray.h>
#include <geometry_msgs/Pose.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/MarkerArray.h>
#include <xmlrpcpp/XmlRpcValue.h>

namespace clutterseg_ros {

// Names in the node's private namespace that are the node's own settings, not clutterseg::Params.
bool is_node_setting(const std::string& name);

// The private namespace's parameters (a dictionary as ros::param::get returns it) as clutterseg::Params.
// Node settings are left out; the rest must be the nested names of `clutterseg --dump-config`.
// Everything is checked by clutterseg::params_from_json; throws clutterseg::Error naming the ROS
// parameter (e.g. "/clutterseg/graph/theta_c") on an unknown name or a wrong value.
clutterseg::Params params_from_ros(const XmlRpc::XmlRpcValue& private_params, const std::string& ns);

// The depth units the node accepts (REP 118): 16UC1/mono16 in millimetres, 32FC1 in metres.
std::optional<double> depth_unit_m(const std::string& encoding);

// Why a depth image and its CameraInfo cannot be segmented (encoding, size, intrinsics), or nothing.
std::optional<std::string> check_depth_frame(const sensor_msgs::Image& image, const sensor_msgs::CameraInfo& info);

// Intrinsics from CameraInfo's K (the depth image is assumed rectified, D is not applied).
clutterseg::Camera camera_from_info(const sensor_msgs::CameraInfo& info, double depth_unit_m);

// The label image's ids for each library object id: view_id[object id] (0 = not in the view). The view is
// r.object_labels or its objects-only copy, whatever the node publishes.
std::vector<int> view_ids(const cv::Mat& object_labels, const cv::Mat& view);

// Objects of one frame in the frame `to_frame` (camera_to_frame maps camera coordinates into it).
// Lists the objects that have a label in the view (view_id > 0), with the view's ids.
ObjectArray objects_message(const clutterseg::Result& r, const std::vector<int>& view_id,
                            const Eigen::Isometry3d& camera_to_frame, const std_msgs::Header& header);

// The support plane as a pose for RViz: z along the plane's normal (towards the camera), the origin on
// the plane below the table's centroid (or below the camera when the table is not an object).
geometry_msgs::Pose plane_pose(const clutterseg::Result& r, const Eigen::Isometry3d& camera_to_frame);

// One cube per listed object (coloured as the debug overlay), its id as text, and the table as a grey
// cube when it is not listed; starts with DELETEALL so objects of the previous frame disappear.
visualization_msgs::MarkerArray markers_message(const ObjectArray& objects, const clutterseg::Result& r,
                                                const Eigen::Isometry3d& camera_to_frame);

// Organized cloud (camera frame): float32 x, y, z (NaN without a measurement) and uint32 label.
sensor_msgs::PointCloud2 cloud_message(const cv::Mat& points, const cv::Mat& view, const std_msgs::Header& header);

}  // namespace clutterseg_ros
