// SPDX-License-Identifier: LGPL-2.1-or-later
#include "dataset.hpp"
#include "metrics.hpp"

#include <json-glib/json-glib.h>

#include <cmath>
#include <memory>
#include <set>
#include <sstream>

namespace pickdetect::eval {
namespace {

constexpr double kFractionSlack = 0.01;

template <typename T> struct GObjectDeleter {
  void operator()(T* p) const { g_object_unref(p); }
};
template <typename T> using GObjectPtr = std::unique_ptr<T, GObjectDeleter<T>>;

const char* kind_of(JsonNode* node) {
  switch (json_node_get_node_type(node)) {
  case JSON_NODE_OBJECT:
    return "an object";
  case JSON_NODE_ARRAY:
    return "an array";
  case JSON_NODE_NULL:
    return "null";
  case JSON_NODE_VALUE:
    break;
  }
  const GType t = json_node_get_value_type(node);
  if (t == G_TYPE_STRING)
    return "a string";
  if (t == G_TYPE_BOOLEAN)
    return "a boolean";
  return "a number";
}

/// Walks a parsed document, naming the file and the field path in every error.
class Reader {
public:
  explicit Reader(std::string origin) : origin_(std::move(origin)) {}

  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw FormatError(origin_ + ": " + (field.empty() ? std::string("top level") : field) + ": " +
                      what);
  }

  JsonObject* object(JsonNode* node, const std::string& field) const {
    if (!node || !JSON_NODE_HOLDS_OBJECT(node))
      fail(field, std::string("expected an object, got ") + (node ? kind_of(node) : "nothing"));
    return json_node_get_object(node);
  }

  JsonArray* array(JsonNode* node, const std::string& field) const {
    if (!node || !JSON_NODE_HOLDS_ARRAY(node))
      fail(field, std::string("expected an array, got ") + (node ? kind_of(node) : "nothing"));
    return json_node_get_array(node);
  }

  static JsonNode* member(JsonObject* o, const char* key) {
    return json_object_has_member(o, key) ? json_object_get_member(o, key) : nullptr;
  }

  JsonNode* required(JsonObject* o, const char* key, const std::string& parent) const {
    JsonNode* n = member(o, key);
    if (!n)
      fail(join(parent, key), "missing");
    return n;
  }

  static std::string join(const std::string& parent, const std::string& key) {
    return parent.empty() ? key : parent + "." + key;
  }

  std::string string(JsonNode* node, const std::string& field) const {
    if (!node || !JSON_NODE_HOLDS_VALUE(node) || json_node_get_value_type(node) != G_TYPE_STRING)
      fail(field, std::string("expected a string, got ") + (node ? kind_of(node) : "nothing"));
    return json_node_get_string(node);
  }

  double number(JsonNode* node, const std::string& field) const {
    if (!node || !JSON_NODE_HOLDS_VALUE(node))
      fail(field, std::string("expected a number, got ") + (node ? kind_of(node) : "nothing"));
    const GType t = json_node_get_value_type(node);
    double v = 0.0;
    if (t == G_TYPE_INT64)
      v = static_cast<double>(json_node_get_int(node));
    else if (t == G_TYPE_DOUBLE)
      v = json_node_get_double(node);
    else
      fail(field, std::string("expected a number, got ") + kind_of(node));
    if (!std::isfinite(v))
      fail(field, "not a finite number");
    return v;
  }

  double fraction(JsonNode* node, const std::string& field) const {
    const double v = number(node, field);
    // Rounding in the generator may leave a fraction a little beyond [0, 1].
    if (v < -kFractionSlack || v > 1.0 + kFractionSlack)
      fail(field, "expected a fraction between 0 and 1, got " + format(v));
    return v;
  }

  int integer(JsonNode* node, const std::string& field) const {
    const double v = number(node, field);
    if (v != std::floor(v) || std::abs(v) > 1e9)
      fail(field, "expected an integer, got " + format(v));
    return static_cast<int>(v);
  }

  bool boolean(JsonNode* node, const std::string& field) const {
    if (!node || !JSON_NODE_HOLDS_VALUE(node) || json_node_get_value_type(node) != G_TYPE_BOOLEAN)
      fail(field, std::string("expected true or false, got ") + (node ? kind_of(node) : "nothing"));
    return json_node_get_boolean(node);
  }

  Point point(JsonNode* node, const std::string& field) const {
    JsonArray* a = array(node, field);
    if (json_array_get_length(a) != 2)
      fail(field,
           "expected an [x, y] pair, got " + std::to_string(json_array_get_length(a)) + " numbers");
    return {number(json_array_get_element(a, 0), field + "[0]"),
            number(json_array_get_element(a, 1), field + "[1]")};
  }

  std::vector<Point> points(JsonNode* node, const std::string& field) const {
    JsonArray* a = array(node, field);
    std::vector<Point> out;
    for (guint i = 0; i < json_array_get_length(a); ++i)
      out.push_back(point(json_array_get_element(a, i), field + "[" + std::to_string(i) + "]"));
    return out;
  }

  Polygon polygon(JsonNode* node, const std::string& field) const {
    Polygon p = points(node, field);
    if (p.size() < 3)
      fail(field, "a polygon needs at least 3 points, got " + std::to_string(p.size()));
    return p;
  }

  static std::string format(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  }

private:
  std::string origin_;
};

JsonNode* parse_root(JsonParser* parser, const std::string& text, const std::string& origin) {
  GError* error = nullptr;
  if (!json_parser_load_from_data(parser, text.data(), static_cast<gssize>(text.size()), &error)) {
    const std::string message = error ? error->message : "unknown error";
    g_clear_error(&error);
    throw FormatError(origin + ": not valid JSON: " + message);
  }
  JsonNode* root = json_parser_get_root(parser);
  if (!root)
    throw FormatError(origin + ": empty file");
  return root;
}

std::string read_file(const std::string& path) {
  gchar* contents = nullptr;
  gsize length = 0;
  GError* error = nullptr;
  if (!g_file_get_contents(path.c_str(), &contents, &length, &error)) {
    const std::string message = error ? error->message : "cannot be read";
    g_clear_error(&error);
    throw FormatError(path + ": " + message);
  }
  std::string text(contents, length);
  g_free(contents);
  return text;
}

DetectedInstance parse_detected(const Reader& r, JsonNode* node, const std::string& field) {
  JsonObject* o = r.object(node, field);
  DetectedInstance d;
  d.model = r.string(r.required(o, "model", field), Reader::join(field, "model"));
  d.points = r.points(r.required(o, "points", field), Reader::join(field, "points"));
  if (d.points.empty())
    r.fail(Reader::join(field, "points"), "needs at least the centre");
  d.polygon = r.polygon(r.required(o, "polygon", field), Reader::join(field, "polygon"));
  if (JsonNode* n = Reader::member(o, "score"))
    d.score = r.number(n, Reader::join(field, "score"));
  if (JsonNode* n = Reader::member(o, "matches"))
    d.matches = r.integer(n, Reader::join(field, "matches"));
  if (JsonNode* n = Reader::member(o, "pickable"))
    d.pickable = r.boolean(n, Reader::join(field, "pickable"));
  if (JsonNode* n = Reader::member(o, "track"))
    d.track = static_cast<long long>(r.number(n, Reader::join(field, "track")));
  return d;
}

void add_points(JsonBuilder* b, const char* key, const std::vector<Point>& points) {
  json_builder_set_member_name(b, key);
  json_builder_begin_array(b);
  for (const Point& p : points) {
    json_builder_begin_array(b);
    json_builder_add_double_value(b, p.x);
    json_builder_add_double_value(b, p.y);
    json_builder_end_array(b);
  }
  json_builder_end_array(b);
}

} // namespace

const ModelInfo* Dataset::find_model(const std::string& model) const {
  for (const ModelInfo& m : models)
    if (m.name == model)
      return &m;
  return nullptr;
}

std::string Dataset::path_of(const std::string& relative) const {
  if (g_path_is_absolute(relative.c_str()))
    return relative;
  gchar* joined = g_build_filename(dir.c_str(), relative.c_str(), nullptr);
  std::string out(joined);
  g_free(joined);
  return out;
}

Dataset parse_dataset(const std::string& text, const std::string& origin, const std::string& dir) {
  GObjectPtr<JsonParser> parser(json_parser_new());
  JsonNode* root_node = parse_root(parser.get(), text, origin);
  const Reader r(origin);
  JsonObject* root = r.object(root_node, "");

  Dataset ds;
  ds.file = origin;
  ds.dir = dir;
  if (JsonNode* n = Reader::member(root, "name"))
    ds.name = r.string(n, "name");
  else {
    gchar* base = g_path_get_basename(dir.c_str());
    ds.name = base;
    g_free(base);
  }

  if (JsonNode* n = Reader::member(root, "fps")) {
    ds.fps = r.number(n, "fps");
    if (!(*ds.fps > 0.0))
      r.fail("fps", "must be positive");
  }

  JsonObject* models = r.object(r.required(root, "models", ""), "models");
  GList* names = json_object_get_members(models);
  for (GList* it = names; it; it = it->next) {
    const std::string name = static_cast<const char*>(it->data);
    const std::string field = "models." + name;
    JsonObject* m = r.object(json_object_get_member(models, name.c_str()), field);
    ModelInfo info;
    info.name = name;
    info.image = r.string(r.required(m, "image", field), field + ".image");
    info.principal_points =
        r.points(r.required(m, "principal_points", field), field + ".principal_points");
    if (info.principal_points.empty())
      r.fail(field + ".principal_points", "needs at least the object centre");
    info.polygon = r.polygon(r.required(m, "polygon", field), field + ".polygon");
    ds.models.push_back(std::move(info));
  }
  g_list_free(names);
  if (ds.models.empty())
    r.fail("models", "no model");

  JsonArray* scenes = r.array(r.required(root, "scenes", ""), "scenes");
  std::set<std::string> images;
  for (guint si = 0; si < json_array_get_length(scenes); ++si) {
    const std::string field = "scenes[" + std::to_string(si) + "]";
    JsonObject* s = r.object(json_array_get_element(scenes, si), field);
    Scene scene;
    scene.image = r.string(r.required(s, "image", field), field + ".image");
    if (!images.insert(scene.image).second)
      r.fail(field + ".image", "'" + scene.image + "' is listed twice");
    scene.width = r.integer(r.required(s, "width", field), field + ".width");
    scene.height = r.integer(r.required(s, "height", field), field + ".height");
    if (scene.width <= 0)
      r.fail(field + ".width", "must be positive");
    if (scene.height <= 0)
      r.fail(field + ".height", "must be positive");
    JsonArray* instances = r.array(r.required(s, "instances", field), field + ".instances");
    for (guint ii = 0; ii < json_array_get_length(instances); ++ii) {
      const std::string f = field + ".instances[" + std::to_string(ii) + "]";
      JsonObject* o = r.object(json_array_get_element(instances, ii), f);
      TrueInstance t;
      t.model = r.string(r.required(o, "model", f), f + ".model");
      const ModelInfo* model = ds.find_model(t.model);
      if (!model)
        r.fail(f + ".model", "'" + t.model + "' is not one of the dataset's models");
      t.visible = r.fraction(r.required(o, "visible", f), f + ".visible");
      t.points = r.points(r.required(o, "points", f), f + ".points");
      // A don't-care instance (a look-alike surface listed with visible 0) may leave its points
      // out: it is never scored by them.
      const bool dont_care_without_points = t.points.empty() && t.visible < kDontCareVisible;
      if (t.points.size() != model->principal_points.size() && !dont_care_without_points)
        r.fail(f + ".points",
               "has " + std::to_string(t.points.size()) + " points but model '" + t.model +
                   "' has " + std::to_string(model->principal_points.size()) + " principal points");
      t.polygon = r.polygon(r.required(o, "polygon", f), f + ".polygon");
      if (JsonNode* n = Reader::member(o, "covered"))
        t.covered = r.fraction(n, f + ".covered");
      if (JsonNode* n = Reader::member(o, "in_frame"))
        t.in_frame = r.fraction(n, f + ".in_frame");
      if (JsonNode* n = Reader::member(o, "z"))
        t.z = r.integer(n, f + ".z");
      if (JsonNode* n = Reader::member(o, "angle"))
        t.angle = r.number(n, f + ".angle");
      if (JsonNode* n = Reader::member(o, "scale"))
        t.scale = r.number(n, f + ".scale");
      if (JsonNode* n = Reader::member(o, "tilt"))
        t.tilt = r.number(n, f + ".tilt");
      if (JsonNode* n = Reader::member(o, "track"))
        t.track = r.integer(n, f + ".track");
      else if (ds.fps)
        r.fail(f + ".track", "missing (a video sequence, with fps, gives every instance one)");
      scene.instances.push_back(std::move(t));
    }
    ds.scenes.push_back(std::move(scene));
  }
  return ds;
}

Dataset load_dataset(const std::string& dir_or_file) {
  std::string file = dir_or_file;
  std::string dir = dir_or_file;
  if (g_file_test(dir_or_file.c_str(), G_FILE_TEST_IS_DIR)) {
    gchar* joined = g_build_filename(dir_or_file.c_str(), "dataset.json", nullptr);
    file = joined;
    g_free(joined);
  } else {
    gchar* parent = g_path_get_dirname(dir_or_file.c_str());
    dir = parent;
    g_free(parent);
  }
  if (!g_file_test(file.c_str(), G_FILE_TEST_EXISTS))
    throw FormatError(file + ": no such file (a dataset folder holds dataset.json)");
  return parse_dataset(read_file(file), file, dir);
}

std::vector<SceneDetections> parse_detections(const std::string& text, const std::string& origin) {
  std::vector<SceneDetections> out;
  std::istringstream lines(text);
  std::string line;
  int number = 0;
  while (std::getline(lines, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos)
      continue;
    const std::string where = origin + ":" + std::to_string(number);
    GObjectPtr<JsonParser> parser(json_parser_new());
    JsonNode* root_node = parse_root(parser.get(), line, where);
    const Reader r(where);
    JsonObject* root = r.object(root_node, "");
    SceneDetections scene;
    scene.image = r.string(r.required(root, "image", ""), "image");
    if (JsonNode* n = Reader::member(root, "method"))
      scene.method = r.string(n, "method");
    if (JsonNode* n = Reader::member(root, "ms")) {
      JsonObject* ms = r.object(n, "ms");
      GList* names = json_object_get_members(ms);
      for (GList* it = names; it; it = it->next) {
        const char* name = static_cast<const char*>(it->data);
        scene.ms[name] = r.number(json_object_get_member(ms, name), std::string("ms.") + name);
      }
      g_list_free(names);
    }
    if (JsonNode* n = Reader::member(root, "frame_ms"))
      scene.frame_ms = r.number(n, "frame_ms");
    JsonArray* instances = r.array(r.required(root, "instances", ""), "instances");
    for (guint i = 0; i < json_array_get_length(instances); ++i)
      scene.instances.push_back(parse_detected(r, json_array_get_element(instances, i),
                                               "instances[" + std::to_string(i) + "]"));
    out.push_back(std::move(scene));
  }
  return out;
}

std::vector<SceneDetections> load_detections(const std::string& path) {
  return parse_detections(read_file(path), path);
}

std::string detections_line(const SceneDetections& scene) {
  GObjectPtr<JsonBuilder> b(json_builder_new());
  json_builder_begin_object(b.get());
  json_builder_set_member_name(b.get(), "image");
  json_builder_add_string_value(b.get(), scene.image.c_str());
  if (!scene.method.empty()) {
    json_builder_set_member_name(b.get(), "method");
    json_builder_add_string_value(b.get(), scene.method.c_str());
  }
  if (!scene.ms.empty()) {
    json_builder_set_member_name(b.get(), "ms");
    json_builder_begin_object(b.get());
    for (const auto& [model, ms] : scene.ms) {
      json_builder_set_member_name(b.get(), model.c_str());
      json_builder_add_double_value(b.get(), ms);
    }
    json_builder_end_object(b.get());
  }
  if (scene.frame_ms) {
    json_builder_set_member_name(b.get(), "frame_ms");
    json_builder_add_double_value(b.get(), *scene.frame_ms);
  }
  json_builder_set_member_name(b.get(), "instances");
  json_builder_begin_array(b.get());
  for (const DetectedInstance& d : scene.instances) {
    json_builder_begin_object(b.get());
    json_builder_set_member_name(b.get(), "model");
    json_builder_add_string_value(b.get(), d.model.c_str());
    add_points(b.get(), "points", d.points);
    add_points(b.get(), "polygon", d.polygon);
    json_builder_set_member_name(b.get(), "score");
    json_builder_add_double_value(b.get(), d.score);
    json_builder_set_member_name(b.get(), "matches");
    json_builder_add_int_value(b.get(), d.matches);
    json_builder_set_member_name(b.get(), "pickable");
    json_builder_add_boolean_value(b.get(), d.pickable);
    if (d.track) {
      json_builder_set_member_name(b.get(), "track");
      json_builder_add_int_value(b.get(), *d.track);
    }
    json_builder_end_object(b.get());
  }
  json_builder_end_array(b.get());
  json_builder_end_object(b.get());

  GObjectPtr<JsonGenerator> gen(json_generator_new());
  JsonNode* root = json_builder_get_root(b.get());
  json_generator_set_root(gen.get(), root);
  gchar* text = json_generator_to_data(gen.get(), nullptr);
  std::string out(text);
  g_free(text);
  json_node_unref(root);
  return out;
}

} // namespace pickdetect::eval
