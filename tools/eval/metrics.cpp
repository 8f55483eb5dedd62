// SPDX-License-Identifier: LGPL-2.1-or-later
#include "metrics.hpp"

#include "tracking.hpp"

#include <json-glib/json-glib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>
#include <tuple>

namespace pickdetect::eval {
namespace {

std::optional<double> ratio(double num, double den) {
  if (den <= 0.0)
    return std::nullopt;
  return num / den;
}

double percentile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  const double rank = p * static_cast<double>(values.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(rank));
  const size_t hi = std::min(lo + 1, values.size() - 1);
  const double frac = rank - static_cast<double>(lo);
  return values[lo] + (values[hi] - values[lo]) * frac;
}

bool scene_covered_known(const Scene& scene) {
  return std::all_of(scene.instances.begin(), scene.instances.end(),
                     [](const TrueInstance& t) { return t.covered.has_value(); });
}

bool required(const TrueInstance& t) {
  return t.visible >= kDontCareVisible;
}

void add_number(JsonBuilder* b, const char* key, const std::optional<double>& v) {
  json_builder_set_member_name(b, key);
  if (v)
    json_builder_add_double_value(b, *v);
  else
    json_builder_add_null_value(b);
}

void add_summary(JsonBuilder* b, const Summary& s) {
  json_builder_begin_object(b);
  add_number(b, "object_precision", s.object_precision);
  add_number(b, "object_recall", s.object_recall);
  add_number(b, "pixel_precision", s.pixel_precision);
  add_number(b, "pixel_recall", s.pixel_recall);
  add_number(b, "center_mean_px", s.center_mean_px);
  add_number(b, "center_p95_px", s.center_p95_px);
  add_number(b, "points_mean_px", s.points_mean_px);
  add_number(b, "pick_precision", s.pick_precision);
  add_number(b, "pick_recall", s.pick_recall);
  json_builder_set_member_name(b, "tp");
  json_builder_add_int_value(b, s.tp);
  json_builder_set_member_name(b, "fp");
  json_builder_add_int_value(b, s.fp);
  json_builder_set_member_name(b, "fn");
  json_builder_add_int_value(b, s.fn);
  add_number(b, "ms_per_frame", s.ms_per_frame);
  json_builder_end_object(b);
}

std::string to_text(JsonBuilder* b, int indent) {
  JsonGenerator* gen = json_generator_new();
  JsonNode* root = json_builder_get_root(b);
  json_generator_set_root(gen, root);
  if (indent > 0) {
    json_generator_set_pretty(gen, TRUE);
    json_generator_set_indent(gen, static_cast<guint>(indent));
  }
  gchar* text = json_generator_to_data(gen, nullptr);
  std::string out(text);
  g_free(text);
  json_node_unref(root);
  g_object_unref(gen);
  return out;
}

std::string percent(const std::optional<double>& v) {
  if (!v)
    return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", *v * 100.0);
  return buf;
}

std::string fixed3(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}

std::string pixels(const std::optional<double>& v) {
  if (!v)
    return "-";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", *v);
  return buf;
}

/// Methods in a fixed order: the paper's, then any other by name.
std::vector<std::string> method_order(const std::map<std::string, Scorer>& scorers) {
  static const char* known[] = {"ransac-all", "ransac-clustered", "voting"};
  std::vector<std::string> out;
  for (const char* k : known)
    if (scorers.count(k))
      out.push_back(k);
  for (const auto& kv : scorers)
    if (std::find(out.begin(), out.end(), kv.first) == out.end())
      out.push_back(kv.first);
  return out;
}

} // namespace

void Tally::add(const Tally& o) {
  tp += o.tp;
  fp += o.fp;
  required += o.required;
  tp_intersection += o.tp_intersection;
  counted_detected += o.counted_detected;
  required_true += o.required_true;
  center_errors.insert(center_errors.end(), o.center_errors.begin(), o.center_errors.end());
  point_error_sum += o.point_error_sum;
  point_count += o.point_count;
  pickable_flagged += o.pickable_flagged;
  pickable_safe += o.pickable_safe;
  pick_required += o.pick_required;
  pick_found += o.pick_found;
  ms.insert(ms.end(), o.ms.begin(), o.ms.end());
}

Summary Tally::summary() const {
  Summary s;
  s.tp = tp;
  s.fp = fp;
  s.fn = required - tp;
  s.object_precision = ratio(static_cast<double>(tp), static_cast<double>(tp + fp));
  s.object_recall = ratio(static_cast<double>(tp), static_cast<double>(required));
  s.pixel_precision = ratio(tp_intersection, counted_detected);
  s.pixel_recall = ratio(tp_intersection, required_true);
  if (!center_errors.empty()) {
    double sum = 0.0;
    for (double e : center_errors)
      sum += e;
    s.center_mean_px = sum / static_cast<double>(center_errors.size());
    s.center_p95_px = percentile(center_errors, 0.95);
  }
  s.points_mean_px = ratio(point_error_sum, static_cast<double>(point_count));
  s.pick_precision =
      ratio(static_cast<double>(pickable_safe), static_cast<double>(pickable_flagged));
  s.pick_recall = ratio(static_cast<double>(pick_found), static_cast<double>(pick_required));
  if (!ms.empty())
    s.ms_per_frame = percentile(ms, 0.5);
  return s;
}

std::vector<Pairing> match_scene(const Scene& scene, const std::vector<DetectedInstance>& detected,
                                 const std::string& model) {
  std::vector<Pairing> pairs(detected.size());
  // Candidate pairs: (IoU, detection, instance).
  std::vector<std::tuple<double, size_t, size_t>> candidates;
  for (size_t d = 0; d < detected.size(); ++d) {
    if (detected[d].model != model)
      continue;
    for (size_t g = 0; g < scene.instances.size(); ++g) {
      if (scene.instances[g].model != model)
        continue;
      const double iou =
          frame_overlap(detected[d].polygon, scene.instances[g].polygon, scene.width, scene.height)
              .iou();
      if (iou >= kMatchIoU)
        candidates.emplace_back(iou, d, g);
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
    if (std::get<0>(a) != std::get<0>(b))
      return std::get<0>(a) > std::get<0>(b);
    if (std::get<1>(a) != std::get<1>(b))
      return std::get<1>(a) < std::get<1>(b);
    return std::get<2>(a) < std::get<2>(b);
  });
  std::vector<bool> taken(scene.instances.size(), false);
  for (const auto& [iou, d, g] : candidates) {
    if (pairs[d].instance >= 0 || taken[g])
      continue;
    pairs[d].instance = static_cast<int>(g);
    pairs[d].iou = iou;
    taken[g] = true;
  }
  return pairs;
}

Scorer::Scorer(const Dataset& dataset) : dataset_(dataset) {
  for (const ModelInfo& m : dataset.models)
    tallies_[m.name];
}

void Scorer::add_scene(size_t scene_index, const std::vector<DetectedInstance>& detected,
                       const std::string& model) {
  auto it = tallies_.find(model);
  if (it == tallies_.end())
    throw FormatError("model '" + model + "' is not one of the dataset's models");
  Tally& t = it->second;
  const Scene& scene = dataset_.scenes.at(scene_index);
  const double w = scene.width, h = scene.height;
  const bool pick_known = scene_covered_known(scene);
  const std::vector<Pairing> pairs = match_scene(scene, detected, model);
  std::vector<DetectedInstance>& kept = detections_[scene_index];
  for (const DetectedInstance& det : detected)
    if (det.model == model)
      kept.push_back(det);

  std::vector<int> paired_detection(scene.instances.size(), -1);
  for (size_t d = 0; d < detected.size(); ++d) {
    const DetectedInstance& det = detected[d];
    if (det.model != model)
      continue;
    const int g = pairs[d].instance;
    if (g >= 0)
      paired_detection[static_cast<size_t>(g)] = static_cast<int>(d);
    if (pick_known && det.pickable) {
      ++t.pickable_flagged;
      if (g >= 0 && *scene.instances[static_cast<size_t>(g)].covered < kPickCovered)
        ++t.pickable_safe;
    }
    if (g < 0) {
      ++t.fp;
      t.counted_detected += frame_area(det.polygon, w, h);
      continue;
    }
    const TrueInstance& truth = scene.instances[static_cast<size_t>(g)];
    if (!required(truth))
      continue; // Don't care: counts neither way.
    ++t.tp;
    const Overlap o = frame_overlap(det.polygon, truth.polygon, w, h);
    t.tp_intersection += o.intersection;
    t.counted_detected += o.area_a;
    t.center_errors.push_back(distance(det.points[0], truth.points[0]));
    center_by_truth_[{scene_index, static_cast<size_t>(g)}] = t.center_errors.back();
    const size_t n = std::min(det.points.size(), truth.points.size());
    for (size_t i = 0; i < n; ++i) {
      t.point_error_sum += distance(det.points[i], truth.points[i]);
      ++t.point_count;
    }
  }
  for (size_t g = 0; g < scene.instances.size(); ++g) {
    const TrueInstance& truth = scene.instances[g];
    if (truth.model != model || !required(truth))
      continue;
    ++t.required;
    t.required_true += frame_area(truth.polygon, w, h);
    if (pick_known && *truth.covered < kPickCovered) {
      ++t.pick_required;
      const int d = paired_detection[g];
      if (d >= 0 && detected[static_cast<size_t>(d)].pickable)
        ++t.pick_found;
    }
  }
}

void Scorer::add_scene(size_t scene_index, const std::vector<DetectedInstance>& detected) {
  for (const DetectedInstance& d : detected)
    if (!tallies_.count(d.model))
      throw FormatError("model '" + d.model + "' is not one of the dataset's models");
  for (const ModelInfo& m : dataset_.models)
    add_scene(scene_index, detected, m.name);
}

void Scorer::add_time(size_t scene_index, const std::string& model, double ms) {
  auto it = tallies_.find(model);
  if (it == tallies_.end())
    throw FormatError("model '" + model + "' is not one of the dataset's models");
  it->second.ms.push_back(ms);
  frame_ms_[scene_index] += ms;
}

void Scorer::add_frame_time(size_t scene_index, double ms) {
  if (scene_index >= dataset_.scenes.size())
    throw FormatError("scene " + std::to_string(scene_index) + " is not in the dataset");
  frame_ms_[scene_index] += ms;
}

Summary Scorer::model_summary(const std::string& model) const {
  auto it = tallies_.find(model);
  return it == tallies_.end() ? Summary() : it->second.summary();
}

Summary Scorer::overall() const {
  Tally all;
  for (const auto& kv : tallies_)
    all.add(kv.second);
  all.ms.clear();
  for (const auto& kv : frame_ms_)
    all.ms.push_back(kv.second);
  return all.summary();
}

PairedCenters paired_centers(const std::map<std::string, Scorer>& scorers) {
  PairedCenters out;
  if (scorers.empty())
    return out;
  std::map<std::string, double> sums;
  for (const auto& entry : scorers.begin()->second.center_errors()) {
    // A named key, not a structured binding: C++17 does not let a lambda capture those (clang
    // refuses; the fuzzing build, scripts/fuzz.sh, uses it).
    const auto& key = entry.first;
    const bool everywhere = std::all_of(scorers.begin(), scorers.end(), [&](const auto& kv) {
      return kv.second.center_errors().count(key) > 0;
    });
    if (!everywhere)
      continue;
    ++out.instances;
    for (const auto& [method, scorer] : scorers)
      sums[method] += scorer.center_errors().at(key);
  }
  if (out.instances > 0)
    for (const auto& [method, sum] : sums)
      out.mean_px[method] = sum / static_cast<double>(out.instances);
  return out;
}

std::map<std::string, Scorer> score_detections(const Dataset& dataset,
                                               const std::vector<SceneDetections>& lines) {
  std::map<std::string, size_t> index;
  for (size_t i = 0; i < dataset.scenes.size(); ++i)
    index[dataset.scenes[i].image] = i;
  std::map<std::string, Scorer> scorers;
  std::map<std::string, std::set<size_t>> seen;
  for (const SceneDetections& line : lines) {
    auto it = index.find(line.image);
    if (it == index.end())
      throw FormatError("detections for '" + line.image + "': no such scene in " + dataset.file);
    if (!seen[line.method].insert(it->second).second)
      throw FormatError("detections for '" + line.image + "'" +
                        (line.method.empty() ? "" : " (method " + line.method + ")") +
                        " are listed twice");
    Scorer& s = scorers.try_emplace(line.method, dataset).first->second;
    s.add_scene(it->second, line.instances);
    for (const auto& [model, ms] : line.ms)
      s.add_time(it->second, model, ms);
    if (line.frame_ms)
      s.add_frame_time(it->second, *line.frame_ms);
  }
  // Scenes without a line were seen by the method and nothing was found there.
  for (auto& [method, scorer] : scorers)
    for (size_t i = 0; i < dataset.scenes.size(); ++i)
      if (!seen[method].count(i))
        scorer.add_scene(i, {});
  return scorers;
}

std::string summary_json(const Summary& s, int indent) {
  JsonBuilder* b = json_builder_new();
  add_summary(b, s);
  std::string out = to_text(b, indent);
  g_object_unref(b);
  return out;
}

namespace {

void add_tracking(JsonBuilder* b, const TrackingSummary& t) {
  json_builder_set_member_name(b, "tracking");
  json_builder_begin_object(b);
  for (const auto& [key, v] : {std::pair{"mota", t.mota}, {"idf1", t.idf1}}) {
    json_builder_set_member_name(b, key);
    if (v)
      json_builder_add_double_value(b, *v);
    else
      json_builder_add_null_value(b);
  }
  for (const auto& [key, v] : {std::pair{"id_switches", t.id_switches},
                               {"fragmented", t.fragmented},
                               {"ghosts", t.ghosts},
                               {"objects_present", t.objects_present},
                               {"objects_counted", t.objects_counted},
                               {"required", t.required},
                               {"detections", t.detections},
                               {"fn", t.fn},
                               {"fp", t.fp},
                               {"idtp", t.idtp}}) {
    json_builder_set_member_name(b, key);
    json_builder_add_int_value(b, v);
  }
  json_builder_end_object(b);
}

} // namespace

std::string report_json(const Dataset& dataset, const std::map<std::string, Scorer>& scorers) {
  JsonBuilder* b = json_builder_new();
  json_builder_begin_object(b);
  json_builder_set_member_name(b, "dataset");
  json_builder_add_string_value(b, dataset.name.c_str());
  json_builder_set_member_name(b, "methods");
  json_builder_begin_object(b);
  for (const std::string& method : method_order(scorers)) {
    const Scorer& s = scorers.at(method);
    json_builder_set_member_name(b, method.empty() ? "detections" : method.c_str());
    json_builder_begin_object(b);
    json_builder_set_member_name(b, "overall");
    add_summary(b, s.overall());
    json_builder_set_member_name(b, "models");
    json_builder_begin_object(b);
    for (const ModelInfo& m : dataset.models) {
      json_builder_set_member_name(b, m.name.c_str());
      add_summary(b, s.model_summary(m.name));
    }
    json_builder_end_object(b);
    if (dataset.fps)
      add_tracking(b, score_tracking(dataset, s.detections()));
    json_builder_end_object(b);
  }
  json_builder_end_object(b);
  if (scorers.size() > 1) {
    const PairedCenters paired = paired_centers(scorers);
    json_builder_set_member_name(b, "paired_centers");
    json_builder_begin_object(b);
    json_builder_set_member_name(b, "instances");
    json_builder_add_int_value(b, paired.instances);
    json_builder_set_member_name(b, "center_mean_px");
    json_builder_begin_object(b);
    for (const std::string& method : method_order(scorers)) {
      json_builder_set_member_name(b, method.empty() ? "detections" : method.c_str());
      auto it = paired.mean_px.find(method);
      if (it == paired.mean_px.end())
        json_builder_add_null_value(b);
      else
        json_builder_add_double_value(b, it->second);
    }
    json_builder_end_object(b);
    json_builder_end_object(b);
  }
  json_builder_end_object(b);
  std::string out = to_text(b, 2);
  g_object_unref(b);
  return out;
}

std::string report_table(const Dataset& dataset, const std::map<std::string, Scorer>& scorers) {
  const std::vector<std::string> header = {"object", "method", "obj P", "obj R",  "pix P",
                                           "pix R",  "centre", "c p95", "points", "pick P",
                                           "pick R", "TP",     "FP",    "FN",     "ms/frame"};
  std::vector<std::vector<std::string>> rows;
  auto row = [&](const std::string& object, const std::string& method, const Summary& s) {
    rows.push_back({object, method.empty() ? "detections" : method, percent(s.object_precision),
                    percent(s.object_recall), percent(s.pixel_precision), percent(s.pixel_recall),
                    pixels(s.center_mean_px), pixels(s.center_p95_px), pixels(s.points_mean_px),
                    percent(s.pick_precision), percent(s.pick_recall), std::to_string(s.tp),
                    std::to_string(s.fp), std::to_string(s.fn), pixels(s.ms_per_frame)});
  };
  const std::vector<std::string> methods = method_order(scorers);
  for (const ModelInfo& m : dataset.models)
    for (const std::string& method : methods)
      row(m.name, method, scorers.at(method).model_summary(m.name));
  for (const std::string& method : methods)
    row("overall", method, scorers.at(method).overall());

  std::vector<size_t> width(header.size());
  for (size_t c = 0; c < header.size(); ++c) {
    width[c] = header[c].size();
    for (const auto& r : rows)
      width[c] = std::max(width[c], r[c].size());
  }
  std::ostringstream out;
  auto line = [&](const std::vector<std::string>& cells) {
    out << "|";
    for (size_t c = 0; c < cells.size(); ++c) {
      const size_t pad = width[c] - cells[c].size();
      if (c < 2)
        out << " " << cells[c] << std::string(pad, ' ') << " |";
      else
        out << " " << std::string(pad, ' ') << cells[c] << " |";
    }
    out << "\n";
  };
  line(header);
  out << "|";
  for (size_t c = 0; c < header.size(); ++c)
    out << std::string(width[c] + 1, '-') << (c < 2 ? "-|" : ":|");
  out << "\n";
  for (const auto& r : rows)
    line(r);
  out << "\nobj/pix/pick P and R in %, centre (mean), c p95 and points (mean) in pixels, "
         "ms/frame the median (per model only when each model ran alone, --per-model).\n";
  if (scorers.size() > 1) {
    const PairedCenters paired = paired_centers(scorers);
    out << "\nCentre error on the " << paired.instances
        << " required instances every method found:";
    for (const std::string& method : methods) {
      auto it = paired.mean_px.find(method);
      out << " " << (method.empty() ? "detections" : method) << " "
          << (it == paired.mean_px.end() ? std::string("-") : fixed3(it->second)) << " px"
          << (method == methods.back() ? "." : ",");
    }
    out << "\n";
  }
  if (dataset.fps) {
    out << "\nTracking (" << dataset.scenes.size() << " frames at " << *dataset.fps << " fps):\n";
    for (const std::string& method : methods) {
      const TrackingSummary t = score_tracking(dataset, scorers.at(method).detections());
      auto num = [](const std::optional<double>& v) { return v ? fixed3(*v) : std::string("-"); };
      out << "  " << (method.empty() ? "detections" : method) << ": MOTA " << num(t.mota)
          << ", IDF1 " << num(t.idf1) << ", identity switches " << t.id_switches << ", fragmented "
          << t.fragmented << ", ghost ids " << t.ghosts << ", objects counted " << t.objects_counted
          << " of " << t.objects_present << " present\n";
    }
  }
  return out.str();
}

} // namespace pickdetect::eval
