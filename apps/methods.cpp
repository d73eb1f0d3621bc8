#include "methods.hpp"

#include "clutterseg/objects.hpp"
#include "clutterseg/segmenter.hpp"
#ifdef CLUTTERSEG_WITH_PCL
#include "clutterseg/pcl/baselines.hpp"
#endif

namespace clutterseg::app {

namespace {

Method clutterseg_method(Params params) {
  params.support.objects_only = true;
  auto segmenter = std::make_shared<Segmenter>(params);
  return {"clutterseg", [segmenter, params](const Frame& frame) {
            Result r = segmenter->segment(frame.depth, frame.camera);
            MethodOutput out;
            out.labels = r.object_labels.empty() ? r.patch_labels : objects_only(r.object_labels, r.objects, params.tracking.enabled);
            out.timings_ms = std::move(r.timings_ms);
            return out;
          }};
}

#ifdef CLUTTERSEG_WITH_PCL
// The PCL baselines keep no state between frames; their labels are objects-only already.
MethodOutput from_baseline(baselines::BaselineResult r) { return {std::move(r.labels), std::move(r.timings_ms)}; }

Method lccp_method() {
  return {"lccp", [](const Frame& f) { return from_baseline(baselines::segment_lccp(f.depth, f.camera, f.color)); }};
}

Method organized_method() {
  return {"organized", [](const Frame& f) { return from_baseline(baselines::segment_organized(f.depth, f.camera)); }};
}
#endif

}  // namespace

std::vector<std::string> available_methods() {
  std::vector<std::string> names = {"clutterseg"};
#ifdef CLUTTERSEG_WITH_PCL
  names.push_back("lccp");
  names.push_back("organized");
#endif
  return names;
}

Method make_method(const std::string& name, const Params& params) {
  if (name == "clutterseg") return clutterseg_method(params);
#ifdef CLUTTERSEG_WITH_PCL
  if (name == "lccp") return lccp_method();
  if (name == "organized") return organized_method();
#endif
  std::string known;
  for (const auto& n : available_methods()) known += (known.empty() ? "" : ", ") + n;
  throw Error("unknown method '" + name + "' (this build has: " + known + ")");
}

}  // namespace clutterseg::app
