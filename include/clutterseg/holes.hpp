// Pixels without depth inside an object (beyond the paper, Params::Remaining::hole_px; docs/OBJECTS.md).
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "clutterseg/types.hpp"

namespace clutterseg {

// Gives each unlabelled pixel without depth (depth <= 0 or NaN) the object that encloses it along a row or
// a column: the nearest labelled-or-measured pixels on both sides of its run of such pixels (left and right,
// or above and below) carry the same object id, and the run is at most max_run pixels long. Support and
// background objects never take a pixel, and a pixel enclosed by two different objects (one along the row,
// another along the column) stays 0. So a speckled face seen at a grazing angle and the part of an occluded
// object in the sensor's shadow are whole, while a shadow between an object and the table (table on one
// side) or between two objects stays unlabelled. object_labels: CV_32S 1..M, objects[k - 1] is label k;
// its pixel_count grows by the pixels it takes. Returns the number of pixels labelled. Deterministic.
// shadow_focal = f_x * b [px m] of a structured-light sensor whose projector is b metres along +x of the
// depth camera (negative: along -x; 0 = off): a row's run between a near and a farther object, on the far
// object's side away from the projector and at most f_x b (1/z_near - 1/z_far) + max_run / 2 pixels long, is
// the projector's shadow on the farther object, and is that object's but for the 30 % next to the occluder
// (its side face may be there, unlit too) (Params::Remaining::shadow_baseline).
int fill_depth_holes(cv::Mat& object_labels, const cv::Mat& depth, std::vector<Object>& objects, int max_run,
                     double shadow_focal = 0);

}  // namespace clutterseg
