#include "clutterseg/segmenter.hpp"

#include "clutterseg/adjacency.hpp"
#include "clutterseg/contact.hpp"
#include "clutterseg/coplanarity.hpp"
#include "clutterseg/curvature.hpp"
#include "clutterseg/cutfree.hpp"
#include "clutterseg/edges.hpp"
#include "clutterseg/graph_cut.hpp"
#include "clutterseg/limits.hpp"
#include "clutterseg/normals.hpp"
#include "clutterseg/objects.hpp"
#include "clutterseg/parallel.hpp"
#include "clutterseg/holes.hpp"
#include "clutterseg/remaining.hpp"
#include "clutterseg/seams.hpp"
#include "clutterseg/stopwatch.hpp"
#include "clutterseg/support.hpp"

#include <mutex>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace clutterseg {

namespace {

// The adjacent pairs whose junction is a concave crease or a step.
std::vector<PatchPair> concave_pairs(const std::vector<PairJunction>& junctions) {
  std::vector<PatchPair> pairs;
  for (const PairJunction& j : junctions)
    if (j.kind == Junction::Concave || j.kind == Junction::Step) pairs.push_back(j.pair);
  return pairs;
}

// The patch graph of paper i): every link with its cue, weighted 1/deg and symmetrised; adjacent pairs
// that meet in a concave crease or a step are weighted down (beyond the paper, Params::Convexity), and so
// are the `across` pairs (an object on a top face touching a face below its edge), but not the creases
// inside one open object (`inside`); both sorted.
std::vector<GraphEdge> patch_graph(const std::vector<Patch>& patches, const std::vector<PatchPair>& adjacent,
                                   const std::vector<PairJunction>& junctions, const std::vector<PatchPair>& across,
                                   const std::vector<PatchPair>& inside, const std::vector<PatchPair>& coplanar,
                                   const std::vector<CurvatureLink>& curved, const Params::Convexity& convexity) {
  std::vector<GraphEdge> links;
  for (const auto& [a, b] : adjacent) {
    const PairJunction* j = junction_of(junctions, a, b);
    const bool crease = j && (j->kind == Junction::Concave || j->kind == Junction::Step);
    const bool concave = (crease || std::binary_search(across.begin(), across.end(), PatchPair(a, b))) &&
                         !std::binary_search(inside.begin(), inside.end(), PatchPair(a, b));
    links.push_back({a, b, concave ? Cue::AdjacentConcave : Cue::Adjacent, 0,
                     j ? j->convexity : std::numeric_limits<float>::quiet_NaN()});
  }
  for (const auto& [a, b] : coplanar) links.push_back({a, b, Cue::Coplanar, 0});
  for (const auto& c : curved)
    if (patches[static_cast<size_t>(c.pair.first)].table == patches[static_cast<size_t>(c.pair.second)].table)
      links.push_back({c.pair.first, c.pair.second, c.cue, 0});
  return weight_graph(static_cast<int>(patches.size()), std::move(links), convexity.enabled ? convexity.concave_weight : 1.0);
}

// Pairs of which exactly one patch is table: the table never joins an object (beyond the paper).
std::vector<PatchPair> without_table_links(std::vector<PatchPair> pairs, const std::vector<Patch>& patches) {
  std::erase_if(pairs, [&](const PatchPair& pair) {
    return patches[static_cast<size_t>(pair.first)].table != patches[static_cast<size_t>(pair.second)].table;
  });
  return pairs;
}


}  // namespace

void keep_freed_memory() {
#if defined(__GLIBC__)
  static std::once_flag once;
  std::call_once(once, [] {
    constexpr int kThreshold = 512 << 20;
    mallopt(M_MMAP_THRESHOLD, kThreshold);
    mallopt(M_TRIM_THRESHOLD, kThreshold);
  });
#endif
}

Segmenter::Segmenter(Params params) : params_(std::move(params)), tracker_(params_.tracking) {
  validate(params_);  // every parameter within its documented range (limits.hpp)
  if (params_.keep_freed_memory) keep_freed_memory();
}

Result Segmenter::segment(const cv::Mat& depth_in, const Camera& camera) {
  const Params& p = params_;
  set_threads(p.threads);
  const PixelScale px(camera.fx, camera.fy);
  const int step = px.length(p.normals.step_px), edge_step = px.length(p.edges.step_px);
  const float jump = relative_jump_limit(p.edges, step, camera);
  const float pixel_jump = relative_jump_limit(p.edges, 1, camera);
  cv::Mat depth = checked_metres(depth_in, camera);

  Result r;
  Stopwatch watch(r.timings_ms);
  if (p.smoothing.median) depth = median_depth(depth);                           // a) 3x3 median
  watch.mark("median");
  if (p.smoothing.temporal)                                                       // a) temporal smoothing
    depth = p.smoothing.median ? temporal_.push(std::move(depth), p.smoothing)    // the median's own buffer
                               : temporal_.push(depth, p.smoothing);              // may be the caller's image
  watch.mark("temporal_smoothing");
  r.depth = depth;
  const int ksize = px.odd(p.normals.smooth_ksize);
  r.normals = compute_normals(depth, camera, step, ksize, jump);                 // a) normals
  watch.mark("normals");
  r.edge_value = normal_edge_value(r.normals, edge_step);                        // b) normal edges
  if (p.normals.noise_floor > 0 && median_edge_value(r.edge_value, depth) < p.normals.noise_floor) {
    // A noisy sensor: most of the scene would be edges. Smoothed once more, twice as wide (beyond the
    // paper; timed with the edges).
    r.normals = compute_normals(depth, camera, step, 2 * ksize - 1, jump);
    r.edge_value = normal_edge_value(r.normals, edge_step);
  }
  r.edges = edge_mask(r.edge_value, r.depth, p.edges.theta, pixel_jump);
  watch.mark("edges");
  Patches patches = extract_patches(r.edges, r.depth, camera, r.normals, p.patches,  // c) surface patches
                                    px.area(p.patches.min_size_px));
  r.core_patch_labels = patches.labels;
  r.patches = std::move(patches.patches);
  watch.mark("patches");
  r.points = depth_to_points(depth, camera);                                     // point cloud, for d) to j)
  watch.mark("pointcloud");
  const std::optional<Plane> table = p.support.enabled                           // the table (beyond the paper)
      ? find_support_plane(r.patches, r.points, camera, p.support) : std::nullopt;
  const auto mark_table = [&] {
    if (!table) return;
    for (Patch& patch : r.patches) patch.table = lies_in(patch, r.points, *table, p.support);
    unmark_curved_table(r.patches, p.support);                                   // a bowl's floor is no table
  };
  mark_table();
  const int cut = (table ? cut_off_table(r.edges, r.patches, r.core_patch_labels, r.points, *table, p.support,  // objects
                                         px.area(p.patches.min_size_px)) : 0) +                           // left in it
                  (p.patches.split_band > 0 ? split_at_planes(r.edges, r.patches, r.core_patch_labels, r.points,   // patches
                                                              p.patches.split_band, px.area(p.patches.min_size_px),  // of two
                                                              table, p.support) : 0) +                                // planes,
                  split_at_seams(r.edges, r.patches, r.core_patch_labels, r.edge_value, r.normals, p.patches,  // or of two
                                 px.area(p.patches.min_size_px), r.points, table, p.support);                  // faces
  const auto remeasure = [&] {  // measure again only the patches the cuts went through
    patches = update_patches({r.core_patch_labels, std::move(r.patches)}, r.edges, r.depth, camera, r.normals,
                             p.patches, px.area(p.patches.min_size_px));
    r.core_patch_labels = patches.labels;
    r.patches = std::move(patches.patches);
    mark_table();
  };
  if (cut > 0) remeasure();
  watch.mark("support");
  Assignment assignment;
  std::vector<PatchPair> adjacent, links;
  for (int round = 0; round < 2; ++round) {  // again once a patch two objects share is split (beyond the paper)
    assignment = assign_edge_pixels(r.core_patch_labels, r.points, static_cast<int>(r.patches.size()),  // d) adjacency
                                    px.length(p.adjacency.radius_px), p.adjacency.d_max);
    if (table) release_from_table(assignment.labels, assignment.assigned, r.patches, r.points, *table, p.support);
    adjacent = without_table_links(assignment.adjacent, r.patches);
    watch.mark("assignment");
    links = p.cutfree.enabled ? cut_free_pairs(adjacent, r.patches, r.points, p.cutfree, p.seed) : adjacent;  // e) cut-free
    const bool split = round == 0 && p.cutfree.enabled &&
                       split_cut_patches(r.edges, adjacent, links, r.patches, r.core_patch_labels, r.points, p.cutfree,
                                         px.area(p.patches.min_size_px), table ? table->normal : up_in_camera(camera)) > 0;
    if (split) remeasure();
    watch.mark("cutfree");
    if (!split) break;
  }
  r.patch_labels = assignment.labels;
  const int num_patches = static_cast<int>(r.patches.size());
  const std::vector<PairJunction> junctions = p.convexity.enabled                         // convex or concave
      ? classify_junctions(assignment.contacts, r.points, r.normals, p.convexity, r.patches) : std::vector<PairJunction>{};
  const std::vector<PatchPair> across = p.convexity.enabled                              // a can flush with
      ? contacts_across_tops(junctions, r.patches, r.points, table ? table->normal : up_in_camera(camera), p.convexity)
      : std::vector<PatchPair>{};                                                        // a box's front
  const std::vector<PatchPair> inside = p.curvature.enabled && p.curvature.inside_crease  // a bowl's wall into
      ? creases_inside(r.patches, concave_pairs(junctions), r.points, r.normals, p.curvature.split_inside)  // its floor
      : std::vector<PatchPair>{};
  watch.mark("convexity");
  std::vector<PatchPair> linked = links;
  const std::vector<PatchPair> coplanar = p.coplanarity.enabled                         // f/g) co-planarity
      ? without_table_links(coplanar_pairs(r.patches, linked, r.points, camera, p.coplanarity, p.seed), r.patches)
      : std::vector<PatchPair>{};
  linked.insert(linked.end(), coplanar.begin(), coplanar.end());
  watch.mark("coplanarity");
  const std::vector<CurvatureLink> curved = p.curvature.enabled                          // h) curvature
      ? curvature_links(r.patches, linked, r.patch_labels, r.points, r.normals, camera, p) : std::vector<CurvatureLink>{};
  watch.mark("curvature");
  r.graph = patch_graph(r.patches, links, junctions, across, inside, coplanar, curved, p.convexity);  // i) graph cut
  Partition parts = cut_graph(num_patches, r.graph, p.graph.theta_c);
  if (table) settle_table(r.patches, assignment.adjacent, parts.object_of_node, parts.cut_cost);  // one table
  watch.mark("graph_cut");
  std::optional<TableHint> table_hint;
  if (table) {
    table_hint = TableHint{*table, {}, p.support.pixel_band};
    for (const Patch& patch : r.patches) table_hint->table_patch.push_back(patch.table);
  }
  const OcclusionCheck occlusion{camera, p.coplanarity.behind_tolerance, p.coplanarity.behind_fraction};
  r.object_labels = assign_remaining(r.patch_labels, parts.object_of_node,                       // j) remaining
                                     static_cast<int>(parts.cut_cost.size()), r.points, r.normals, p.remaining,
                                     px.area(p.remaining.tiny_px), table_hint, &occlusion,
                                     p.remaining.gap_px > 0 ? px.length(p.remaining.gap_px) : 0);
  if (table) claim_enclosed_floors(r.object_labels, r.patch_labels, r.patches, parts.object_of_node,  // a pan's floor
                                   px.length(p.adjacency.radius_px), px.length(2), p.support.enclosed_share);
  watch.mark("remaining");
  r.objects = describe_objects(r.object_labels, r.points, parts.object_of_node, parts.cut_cost, camera);  // objects
  r.support_plane = table;
  if (table)                                                                     // table, walls
    classify_objects(r.objects, r.patches, r.object_labels, r.points, support_of(*table, r.patches, r.points, p.support),
                     p.support, px.length(4));
  if (p.remaining.hole_px > 0)                                                   // pixels without depth
    fill_depth_holes(r.object_labels, r.depth, r.objects, px.length(p.remaining.hole_px),  // (beyond the paper)
                     camera.fx * p.remaining.shadow_baseline);
  watch.mark("objects");
  if (p.tracking.enabled && !r.object_labels.empty()) {                          // stable ids (beyond the paper)
    if (p.smoothing.temporal ? temporal_.restarted() : tracked_depth_.empty() || scene_changed(tracked_depth_, depth, p.smoothing))
      tracker_.forget();
    if (!p.smoothing.temporal) tracked_depth_ = depth.clone();
    r.hidden_objects = tracker_.update(r.object_labels, r.objects);
  }
  watch.mark("tracking");
  watch.total();
  return r;
}

Result segment(const cv::Mat& depth, const Camera& camera, const Params& params) {
  Params single = params;
  single.smoothing.temporal = false;
  return Segmenter(single).segment(depth, camera);
}

}  // namespace clutterseg
