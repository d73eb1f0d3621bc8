// Images a person can look at.
#pragma once

#include "clutterseg/segmenter.hpp"

namespace clutterseg {

cv::Mat render_normals(const NormalPlanes& normals);     // xyz -> RGB, black = none
cv::Mat render_edges(const cv::Mat& edges);              // white surfaces, black edges
cv::Mat render_edge_value(const cv::Mat& edge_value);    // grey: 1 (flat) white .. 0.5 and below black
cv::Mat render_labels(const cv::Mat& labels);            // distinct colours per id, black = 0
cv::Mat render_depth(const cv::Mat& depth_m);            // colour-mapped depth, black = none
// Labels blended over a BGR colour image (or over the depth rendering when color is empty).
cv::Mat render_overlay(const cv::Mat& labels, const cv::Mat& color, const cv::Mat& depth_m);
// Patch graph over the patch image: nodes at patch centroids, edges coloured by cue (paper Fig. 5).
cv::Mat render_graph(const Result& result, const Camera& camera);

}  // namespace clutterseg
