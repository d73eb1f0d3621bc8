#include "methods.hpp"

#include "clutterseg/objects.hpp"
#include "clutterseg/segmenter.hpp"

namespace clutterseg::app {

namespace {

Method clutterseg_method(Params params) {
  params.support.objects_only = true;
  auto segmenter = std::make_shared<Segmenter>(params);
  return {"clutterseg", [segmenter](const Frame& frame) {
            Result r = segmenter->segment(frame.depth, frame.camera);
            MethodOutput out;
            out.labels = r.object_labels.empty() ? r.patch_labels : objects_only(r.object_labels, r.objects);
            out.timings_ms = std::move(r.timings_ms);
            return out;
          }};
}

}  // namespace

std::vector<std::string> available_methods() {
  std::vector<std::string> names = {"clutterseg"};
  return names;
}

Method make_method(const std::string& name, const Params& params) {
  if (name == "clutterseg") return clutterseg_method(params);
  throw Error("unknown method '" + name + "' (this build has: clutterseg)");
}

}  // namespace clutterseg::app
