#include "clutterseg/objects.hpp"

namespace clutterseg {

cv::Mat objects_only(const cv::Mat& object_labels, const std::vector<Object>& objects) {
  // New ids keep the order of the old ones, so the view is as stable as the labels it comes from.
  std::vector<int> new_id(objects.size() + 1, 0);
  int next = 0;
  for (const auto& o : objects)
    if (!o.support && !o.background && o.id > 0 && o.id < static_cast<int>(new_id.size())) new_id[static_cast<size_t>(o.id)] = ++next;
  cv::Mat out(object_labels.size(), CV_32S);
  object_labels.forEach<int>([&](const int& id, const int* pos) {
    out.at<int>(pos[0], pos[1]) = id > 0 && id < static_cast<int>(new_id.size()) ? new_id[static_cast<size_t>(id)] : 0;
  });
  return out;
}

}  // namespace clutterseg
