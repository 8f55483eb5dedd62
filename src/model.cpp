// SPDX-License-Identifier: LGPL-2.1-or-later
// The model: picture, mask, principal points, outline, and the model file that stores them.
#include <pickdetect/error.hpp>
#include <pickdetect/features.hpp>
#include <pickdetect/model.hpp>

#include "object_mask.hpp"
#include "open_file_storage.hpp"

#include <opencv2/core/persistence.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdlib>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <utility>

namespace fs = std::filesystem;

namespace pickdetect {
namespace {

/// Longest side of a model picture: beyond this SIFT's cost and memory are out of proportion to
/// what a model needs, and such a picture is almost surely not meant as a model.
constexpr int kMaxModelSide = 4096;
/// Largest distance (pixels) between the alpha contour and its simplified outline.
constexpr double kOutlineTolerancePx = 1.0;
/// Columns of a cached descriptor matrix: SIFT's 128 floats, ORB's 32 bytes.
constexpr int kSiftDescriptorSize = 128;
constexpr int kOrbDescriptorSize = 32;

std::string in_quotes(const std::string& path) {
  return "'" + path + "'";
}

/// Throws an Error naming the file when it cannot be opened for reading.
void require_readable(const std::string& path, const char* what) {
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw Error(std::string(what) + " " + in_quotes(path) + " is a directory, not a file");
  // A FIFO would block the open below until a writer comes; a device may never end.
  if (fs::exists(path, ec) && !fs::is_regular_file(path, ec))
    throw Error(std::string(what) + " " + in_quotes(path) +
                " is not a regular file (a FIFO, socket or device)");
  std::ifstream probe(path, std::ios::binary);
  if (!probe) {
    const int err = errno;
    throw Error(std::string(what) + " " + in_quotes(path) +
                " cannot be opened: " + std::strerror(err ? err : ENOENT));
  }
}

} // namespace

bool is_model_file(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  if (ext == ".gz")
    return is_model_file(fs::path(path).replace_extension().string());
  return ext == ".yml" || ext == ".yaml" || ext == ".xml" || ext == ".json";
}

namespace {

/// The size a PNG or JPEG file declares in its header, read without decoding the picture; none
/// for other formats or a header that does not say (the decoder decides then).
std::optional<std::pair<long, long>> declared_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char b[24] = {};
  in.read(reinterpret_cast<char*>(b), sizeof b);
  auto be16 = [](const unsigned char* p) { return long{p[0]} << 8 | p[1]; };
  auto be32 = [&](const unsigned char* p) { return be16(p) << 16 | be16(p + 2); };
  // PNG: the 8-byte signature, then the IHDR chunk: length, "IHDR", width, height.
  if (in && std::memcmp(b, "\x89PNG\r\n\x1a\n", 8) == 0 && std::memcmp(b + 12, "IHDR", 4) == 0)
    return std::make_pair(be32(b + 16), be32(b + 20));
  if (b[0] != 0xFF || b[1] != 0xD8)
    return std::nullopt;
  // JPEG: segments (0xFF, marker, 2-byte length) up to a start of frame, SOF0-SOF15 but for
  // DHT (C4), JPG (C8) and DAC (CC): precision, height, width. 0xFF before a marker is fill.
  in.clear();
  in.seekg(2);
  unsigned char m[9];
  while (in.read(reinterpret_cast<char*>(m), 4) && m[0] == 0xFF && m[1] != 0xDA) {
    if (m[1] == 0xFF) {
      in.seekg(-3, std::ios::cur);
      continue;
    }
    const bool sof = m[1] >= 0xC0 && m[1] <= 0xCF && m[1] != 0xC4 && m[1] != 0xC8 && m[1] != 0xCC;
    if (sof && in.read(reinterpret_cast<char*>(m + 4), 5))
      return std::make_pair(be16(m + 7), be16(m + 5));
    if (sof || be16(m + 2) < 2)
      break;
    in.seekg(be16(m + 2) - 2, std::ios::cur);
  }
  return std::nullopt;
}

/// Throws when a picture of cols x rows is too large for a model.
void require_model_size(const std::string& path, long cols, long rows) {
  if (cols > kMaxModelSide || rows > kMaxModelSide)
    throw Error("model picture " + in_quotes(path) + " is " + std::to_string(cols) + "x" +
                std::to_string(rows) + " pixels, larger than the " + std::to_string(kMaxModelSide) +
                "-pixel side a model may have");
}

/// Whether a BGR picture has colour: at least kMinChromaShare of its pixels with channels more
/// than kGreyChroma apart (a grey picture saved as RGB, or JPEG noise on one, has none).
bool has_chroma(const cv::Mat& bgr) {
  constexpr int kGreyChroma = 12;
  constexpr double kMinChromaShare = 0.01;
  cv::Mat hi, lo, planes[3];
  cv::split(bgr, planes);
  cv::max(planes[0], planes[1], hi);
  cv::max(hi, planes[2], hi);
  cv::min(planes[0], planes[1], lo);
  cv::min(lo, planes[2], lo);
  const cv::Mat chroma = hi - lo;
  return cv::countNonZero(chroma > kGreyChroma) >=
         kMinChromaShare * static_cast<double>(bgr.total());
}

void load_picture(Model& model) {
  require_readable(model.image_path, "model picture");
  // Refused before decoding when the header tells: a flat 30000 x 30000 PNG is small on disk
  // but would take gigabytes decoded.
  if (const auto size = declared_size(model.image_path))
    require_model_size(model.image_path, size->first, size->second);
  cv::Mat raw = cv::imread(model.image_path, cv::IMREAD_UNCHANGED);
  if (raw.empty())
    throw Error("model picture " + in_quotes(model.image_path) +
                " cannot be decoded as a picture (unknown or corrupt format)");
  require_model_size(model.image_path, raw.cols, raw.rows);
  if (raw.depth() != CV_8U) {
    double lo = 0, hi = 0;
    cv::minMaxLoc(raw.reshape(1), &lo, &hi);
    raw.convertTo(raw, CV_8U, raw.depth() == CV_16U ? 1.0 / 257.0 : (hi > 1.0 ? 1.0 : 255.0));
  }
  cv::Mat alpha;
  switch (raw.channels()) {
  case 1:
    model.image = raw;
    break;
  case 3:
    cv::cvtColor(raw, model.image, cv::COLOR_BGR2GRAY);
    model.colour = raw;
    break;
  case 4:
    cv::cvtColor(raw, model.image, cv::COLOR_BGRA2GRAY);
    cv::cvtColor(raw, model.colour, cv::COLOR_BGRA2BGR);
    cv::extractChannel(raw, alpha, 3);
    break;
  default:
    throw Error("model picture " + in_quotes(model.image_path) + " has " +
                std::to_string(raw.channels()) + " channels; expected 1, 3 or 4");
  }
  if (!model.colour.empty() && !has_chroma(model.colour))
    model.colour.release(); // A grey picture stored as colour: nothing for the colour to tell.
  if (alpha.empty()) {
    model.mask = cv::Mat(model.image.size(), CV_8UC1, cv::Scalar(255));
  } else {
    model.mask = alpha > 0;
    if (cv::countNonZero(model.mask) == 0)
      throw Error("model picture " + in_quotes(model.image_path) +
                  " is fully transparent: its alpha marks no object");
  }
}

cv::Rect2f object_box(const Model& model) {
  cv::Rect box = cv::boundingRect(model.mask);
  return cv::Rect2f(box);
}

std::vector<cv::Point2f> default_principal_points(const Model& model) {
  const cv::Rect2f b = object_box(model);
  return {{b.x + b.width / 2.f, b.y + b.height / 2.f},
          {b.x, b.y},
          {b.x + b.width, b.y},
          {b.x + b.width, b.y + b.height},
          {b.x, b.y + b.height}};
}

std::vector<cv::Point2f> default_outline(const Model& model) {
  const bool whole = cv::countNonZero(model.mask) == model.mask.rows * model.mask.cols;
  if (!whole) {
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(model.mask.clone(), contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    auto largest = std::max_element(contours.begin(), contours.end(), [](auto& a, auto& b) {
      return cv::contourArea(a) < cv::contourArea(b);
    });
    if (largest != contours.end() && largest->size() >= 3) {
      std::vector<cv::Point> simple;
      cv::approxPolyDP(*largest, simple, kOutlineTolerancePx, true);
      if (simple.size() >= 3)
        return std::vector<cv::Point2f>(simple.begin(), simple.end());
    }
  }
  const float w = static_cast<float>(model.image.cols), h = static_cast<float>(model.image.rows);
  return {{0.f, 0.f}, {w, 0.f}, {w, h}, {0.f, h}};
}

std::vector<cv::Point2f> read_points(const cv::FileNode& node, const std::string& origin,
                                     const char* key) {
  std::vector<cv::Point2f> points;
  if (node.empty() || node.isNone())
    return points;
  if (!node.isSeq())
    throw Error(origin + ": '" + key + "' must be a list of [x, y] pairs");
  for (const cv::FileNode& item : node) {
    auto number = [](const cv::FileNode& n) { return n.isReal() || n.isInt(); };
    if (!item.isSeq() || item.size() != 2 || !number(item[0]) || !number(item[1]))
      throw Error(origin + ": '" + key + "' must be a list of [x, y] pairs of numbers");
    const double x = static_cast<double>(item[0]), y = static_cast<double>(item[1]);
    if (!std::isfinite(x) || !std::isfinite(y))
      throw Error(origin + ": '" + key + "' holds a non-finite number");
    points.emplace_back(static_cast<float>(x), static_cast<float>(y));
  }
  return points;
}

void check_geometry(const Model& model, const std::string& origin) {
  const float w = static_cast<float>(model.image.cols), h = static_cast<float>(model.image.rows);
  if (model.principal_points.empty())
    throw Error(origin + ": no principal points (the first one must be the object centre)");
  for (size_t i = 0; i < model.principal_points.size(); ++i) {
    const cv::Point2f p = model.principal_points[i];
    if (p.x < 0.f || p.y < 0.f || p.x > w || p.y > h)
      throw Error(origin + ": principal point " + std::to_string(i) + " (" + std::to_string(p.x) +
                  ", " + std::to_string(p.y) + ") lies outside the " +
                  std::to_string(model.image.cols) + "x" + std::to_string(model.image.rows) +
                  " model picture");
  }
  if (model.outline.size() < 3)
    throw Error(origin + ": the outline needs at least 3 points, it has " +
                std::to_string(model.outline.size()));
  if (std::abs(cv::contourArea(model.outline)) < 1.0)
    throw Error(origin + ": the outline encloses no area");
  if (model.grasp_point < 0 || model.grasp_point >= static_cast<int>(model.principal_points.size()))
    throw Error(origin + ": grasp_point " + std::to_string(model.grasp_point) +
                " is not the index of a principal point (there are " +
                std::to_string(model.principal_points.size()) + ")");
}

/// Reads a cached descriptor matrix (`key`, one row of `cols` per keypoint) once its declared
/// size agrees with `rows`, `cols` and its data: OpenCV allocates rows x cols before it reads the
/// data, so a corrupt header (rows: 2147483647) would otherwise ask for gigabytes.
cv::Mat read_descriptors(const cv::FileNode& node, size_t rows, int cols, const std::string& origin,
                         const char* key) {
  auto declared = [&](const char* field) {
    const cv::FileNode n = node[field];
    return n.isInt() ? static_cast<long long>(static_cast<int>(n)) : -1LL;
  };
  const long long n = static_cast<long long>(rows);
  const bool agree = node.isMap() && declared("rows") == n &&
                     (n == 0 || declared("cols") == cols) && node["data"].isSeq() &&
                     static_cast<long long>(node["data"].size()) == n * declared("cols");
  if (!agree)
    throw Error(origin + ": the cached '" + key + "' is not a " + std::to_string(rows) + "x" +
                std::to_string(cols) + " matrix (one row per cached keypoint)");
  cv::Mat m;
  node >> m;
  return m;
}

} // namespace

/// Appends the SIFT features of the picture's tilted views (Model::max_tilt_deg), found at
/// SIFT's contrast threshold `contrast_threshold`, to `f`.
static void add_tilted_views(const Model& model, const cv::Mat& picture, Features& f,
                             double contrast_threshold) {
  if (!(model.max_tilt_deg > 0.0))
    return;
  // The views on all cores at once, each SIFT run on one (nested in parallel_for_, its own
  // threads stay out): on two cores SIFT's threads gain little on one picture (a pallet's
  // bundles loaded in half the time, docs/performance.md). Gathered in the views' order.
  const std::vector<TiltedView> views = tilted_views(model.max_tilt_deg);
  std::vector<Features> found(views.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(views.size())), [&](const cv::Range& r) {
    for (int i = r.start; i < r.end; ++i)
      found[static_cast<size_t>(i)] =
          features_of_view(picture, model.mask, views[static_cast<size_t>(i)], contrast_threshold);
  });
  for (const Features& v : found) {
    f.keypoints.insert(f.keypoints.end(), v.keypoints.begin(), v.keypoints.end());
    if (!v.descriptors.empty())
      f.descriptors.push_back(v.descriptors);
  }
}

void compute_model_features(Model& model) {
  // A picture with little print (a white glossy carton) yields few keypoints at SIFT's usual
  // threshold, and a frame sees only a part of them: its weaker extrema are kept too, halving
  // the threshold until the picture has enough. A model picture is one clean picture, so its
  // weak extrema are print, not the noise a frame's would be.
  double threshold = kSiftContrastThreshold;
  const cv::Mat picture = detail::continue_object(model.image, model.mask);
  Features f = extract_features(picture, model.mask, FeatureKind::Sift, threshold);
  while (static_cast<int>(f.keypoints.size()) < kModelKeypointTarget &&
         threshold / 2 >= kLeastModelContrastThreshold - 1e-12) {
    threshold /= 2;
    f = extract_features(picture, model.mask, FeatureKind::Sift, threshold);
  }
  if (static_cast<int>(f.keypoints.size()) < kMinModelKeypoints)
    throw Error("model picture " + in_quotes(model.image_path) + " yields only " +
                std::to_string(f.keypoints.size()) + " SIFT keypoints (at least " +
                std::to_string(kMinModelKeypoints) + " are needed): it has too little texture");
  add_tilted_views(model, picture, f, threshold);
  model.contrast_threshold = threshold;
  model.sift = std::move(f);
  model.orb = extract_features(picture, model.mask, FeatureKind::Orb);
}

Model model_from_picture(const std::string& picture_path, const std::string& name) {
  Model model;
  model.image_path = picture_path;
  model.name = name.empty() ? fs::path(picture_path).stem().string() : name;
  load_picture(model);
  model.principal_points = default_principal_points(model);
  model.outline = default_outline(model);
  compute_model_features(model);
  return model;
}

namespace {

/// Reads one model (a model file's root, or one entry of its `views`) from `node`; `product`
/// is the root, whose `height` and `max_tilt` a view takes unless it gives its own. `origin`
/// names the file (and the view) in errors.
Model read_model(const cv::FileNode& node, const cv::FileNode& product, const std::string& path,
                 const std::string& origin) {
  if (!node.isMap() || node["image"].empty())
    throw Error(origin + ": the 'image' key (path of the model picture) is missing");
  if (!node["image"].isString())
    throw Error(origin + ": 'image' must be a string (path of the model picture)");
  // Keys a view may give, else the product's.
  auto either = [&](const char* key) { return node[key].empty() ? product[key] : node[key]; };

  Model model;
  fs::path image = static_cast<std::string>(node["image"]);
  if (image.is_relative())
    image = fs::path(path).parent_path() / image;
  model.image_path = image.lexically_normal().string();
  model.name = product["name"].isString() ? static_cast<std::string>(product["name"])
                                          : fs::path(path).stem().string();
  try {
    load_picture(model);
  } catch (const Error& e) {
    throw Error(origin + ": " + e.what());
  }
  model.principal_points = read_points(node["principal_points"], origin, "principal_points");
  if (model.principal_points.empty())
    model.principal_points = default_principal_points(model);
  if (!node["outline"].empty()) {
    model.outline = read_points(node["outline"], origin, "outline");
    if (model.outline.empty())
      throw Error(origin + ": 'outline' is empty");
  } else {
    model.outline = default_outline(model);
  }
  if (!node["grasp_point"].empty()) {
    if (!node["grasp_point"].isInt())
      throw Error(origin + ": 'grasp_point' must be the index of a principal point");
    model.grasp_point = static_cast<int>(node["grasp_point"]);
  }
  if (const cv::FileNode height = either("height"); !height.empty()) {
    if (!height.isReal() && !height.isInt())
      throw Error(origin + ": 'height' must be a number (millimetres above the work plane)");
    model.height_mm = static_cast<double>(height);
    if (!std::isfinite(model.height_mm) || model.height_mm < 0.0)
      throw Error(origin + ": 'height' must be a finite number of millimetres, 0 or more");
  }
  // A cache written without max_tilt (before it existed) holds the picture's own features only.
  const cv::FileNode tilt = either("max_tilt");
  const bool tilt_given = !tilt.empty();
  if (tilt_given) {
    if (!tilt.isReal() && !tilt.isInt())
      throw Error(origin + ": 'max_tilt' must be a number (degrees off the face's normal)");
    model.max_tilt_deg = static_cast<double>(tilt);
    if (!(model.max_tilt_deg >= 0.0 && model.max_tilt_deg <= kMaxTiltDeg))
      throw Error(origin + ": 'max_tilt' must lie between 0 and " +
                  std::to_string(static_cast<int>(kMaxTiltDeg)) + " degrees");
  }
  check_geometry(model, origin);

  if (!node["keypoints"].empty() && !node["descriptors"].empty()) {
    Features& sift = model.sift;
    cv::read(node["keypoints"], sift.keypoints);
    sift.descriptors = read_descriptors(node["descriptors"], sift.keypoints.size(),
                                        kSiftDescriptorSize, origin, "descriptors");
    if (sift.descriptors.type() != CV_32F ||
        sift.descriptors.rows != static_cast<int>(sift.keypoints.size()) ||
        sift.descriptors.cols != kSiftDescriptorSize)
      throw Error(origin + ": the cached keypoints and descriptors do not agree (" +
                  std::to_string(sift.keypoints.size()) + " keypoints, " +
                  std::to_string(sift.descriptors.rows) + "x" +
                  std::to_string(sift.descriptors.cols) + " descriptors)");
    if (static_cast<int>(sift.keypoints.size()) < kMinModelKeypoints)
      throw Error(origin + ": the cache holds only " + std::to_string(sift.keypoints.size()) +
                  " keypoints (at least " + std::to_string(kMinModelKeypoints) + " are needed)");
    // A cache written before the key existed was found at SIFT's usual threshold.
    const cv::FileNode contrast = node["contrast_threshold"];
    if (!contrast.empty()) {
      if (!contrast.isReal() && !contrast.isInt())
        throw Error(origin + ": 'contrast_threshold' must be a number (SIFT's, 0.04 its default)");
      model.contrast_threshold = static_cast<double>(contrast);
      if (!(model.contrast_threshold > 0.0 && model.contrast_threshold <= 1.0))
        throw Error(origin + ": 'contrast_threshold' must lie above 0 and at most 1");
    }
    if (!tilt_given)
      add_tilted_views(model, detail::continue_object(model.image, model.mask), sift,
                       model.contrast_threshold);
    if (!node["orb_keypoints"].empty() && !node["orb_descriptors"].empty()) {
      cv::read(node["orb_keypoints"], model.orb.keypoints);
      model.orb.descriptors = read_descriptors(node["orb_descriptors"], model.orb.keypoints.size(),
                                               kOrbDescriptorSize, origin, "orb_descriptors");
      if (model.orb.descriptors.rows != static_cast<int>(model.orb.keypoints.size()) ||
          (!model.orb.descriptors.empty() && model.orb.descriptors.type() != CV_8U))
        throw Error(origin + ": the cached ORB keypoints and descriptors do not agree");
    } else {
      model.orb = extract_features(detail::continue_object(model.image, model.mask), model.mask,
                                   FeatureKind::Orb);
    }
  } else {
    try {
      compute_model_features(model);
    } catch (const Error& e) {
      throw Error(origin + ": " + e.what());
    }
  }
  return model;
}

/// The views of a model file's `views` list, each a model of the product.
std::vector<Model> read_views(const cv::FileNode& root, const std::string& path,
                              const std::string& origin) {
  const cv::FileNode list = root["views"];
  if (!root["image"].empty())
    throw Error(origin + ": give either 'image' (one picture) or 'views' (several), not both");
  if (!list.isSeq() || list.size() == 0)
    throw Error(origin + ": 'views' must be a non-empty list of views (each with its 'image')");
  std::vector<Model> views;
  for (size_t i = 0; i < list.size(); ++i) {
    const cv::FileNode item = list[static_cast<int>(i)];
    std::string where = origin + ", views[" + std::to_string(i) + "]";
    if (item.isMap() && item["name"].isString())
      where += " ('" + static_cast<std::string>(item["name"]) + "')";
    else if (item.isMap() && !item["name"].empty())
      throw Error(where + ": a view's 'name' must be a string");
    Model view = read_model(item, root, path, where);
    view.view = item["name"].isString() ? static_cast<std::string>(item["name"])
                                        : fs::path(view.image_path).stem().string();
    if (view.view.empty())
      throw Error(where + ": a view's 'name' must not be empty");
    for (size_t j = 0; j < views.size(); ++j)
      if (views[j].view == view.view)
        throw Error(origin + ": views[" + std::to_string(j) + "] and views[" + std::to_string(i) +
                    "] are both named '" + view.view +
                    "'; give each view a distinct 'name' (by default its picture's file name)");
    views.push_back(std::move(view));
  }
  return views;
}

} // namespace

std::vector<Model> load_views(const std::string& path) {
  if (path.empty())
    throw Error("no model file given");
  if (!is_model_file(path))
    return {model_from_picture(path)};

  require_readable(path, "model file");
  const std::string origin = "model file " + in_quotes(path);
  cv::FileStorage store;
  detail::open_for_reading(store, path, origin);
  try {
    const cv::FileNode root = store.root();
    if (root.isMap() && !root["views"].empty())
      return read_views(root, path, origin);
    return {read_model(root, root, path, origin)};
  } catch (const cv::Exception& e) {
    throw Error(origin + " is not a valid model file: " + e.err);
  }
}

Model load_model(const std::string& path) {
  std::vector<Model> views = load_views(path);
  if (views.size() != 1)
    throw Error("model file " + in_quotes(path) + " lists " + std::to_string(views.size()) +
                " views of '" + views.front().name + "'; load it as a model list (load_models)");
  return std::move(views.front());
}

namespace {

/// Writes one model's picture, points and (with cache_features) features as keys of the open
/// map of `store`; `folder` is the model file's.
void write_model(cv::FileStorage& store, const Model& model, const fs::path& folder,
                 bool cache_features) {
  const fs::path image = fs::absolute(model.image_path);
  const fs::path relative = image.lexically_relative(folder);
  const bool below = !relative.empty() && *relative.begin() != "..";
  store << "image" << (below ? relative.string() : image.string());
  auto write_points = [&](const char* key, const std::vector<cv::Point2f>& points) {
    store << key << "[";
    for (const cv::Point2f& p : points)
      store << "[:" << p.x << p.y << "]";
    store << "]";
  };
  write_points("principal_points", model.principal_points);
  write_points("outline", model.outline);
  store << "grasp_point" << model.grasp_point;
  if (cache_features && !model.sift.keypoints.empty()) {
    store << "contrast_threshold" << model.contrast_threshold;
    cv::write(store, "keypoints", model.sift.keypoints);
    store << "descriptors" << model.sift.descriptors;
    cv::write(store, "orb_keypoints", model.orb.keypoints);
    store << "orb_descriptors" << model.orb.descriptors;
  }
}

} // namespace

void save_model(const Model& model, const std::string& path, bool cache_features) {
  cv::FileStorage store;
  detail::open_for_writing(store, path, "model file " + in_quotes(path));
  store << "name" << model.name;
  if (model.height_mm > 0.0)
    store << "height" << model.height_mm;
  store << "max_tilt" << model.max_tilt_deg;
  write_model(store, model, fs::absolute(path).parent_path(), cache_features);
}

void save_views(const std::vector<Model>& views, const std::string& path, bool cache_features) {
  if (views.empty())
    throw Error("model file " + in_quotes(path) + ": no views to write");
  for (const Model& view : views)
    if (view.name != views.front().name)
      throw Error("model file " + in_quotes(path) + ": the views name two products, '" +
                  views.front().name + "' and '" + view.name + "'");
  cv::FileStorage store;
  detail::open_for_writing(store, path, "model file " + in_quotes(path));
  const Model& first = views.front();
  store << "name" << first.name;
  if (first.height_mm > 0.0)
    store << "height" << first.height_mm;
  store << "max_tilt" << first.max_tilt_deg;
  store << "views"
        << "[";
  const fs::path folder = fs::absolute(path).parent_path();
  for (const Model& view : views) {
    store << "{";
    store << "name" << (view.view.empty() ? fs::path(view.image_path).stem().string() : view.view);
    write_model(store, view, folder, cache_features);
    store << "}";
  }
  store << "]";
}

} // namespace pickdetect
