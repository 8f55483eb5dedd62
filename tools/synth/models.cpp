// SPDX-License-Identifier: LGPL-2.1-or-later
// Model pictures: read, outlined, and made into look-alike families, elongated boxes, bundles
// of identical packs, and pictures no sharper than the scenes.
#include "synth.hpp"

#include <glib.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>

namespace synth {

namespace {

std::string sanitize(const std::string& stem) {
  std::string out;
  for (char c : stem)
    out += (std::isalnum(static_cast<unsigned char>(c)) || c == '-') ? c : '_';
  return out.empty() ? "model" : out;
}

} // namespace

ModelPicture load_model(const std::string& path) {
  cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (raw.empty())
    throw Failure("model picture '" + path + "' cannot be read as a picture");
  if (raw.depth() != CV_8U)
    raw.convertTo(raw, CV_8U, raw.depth() == CV_16U ? 1.0 / 257.0 : 1.0);
  ModelPicture m;
  m.source = path;
  gchar* base = g_path_get_basename(path.c_str());
  std::string stem(base);
  g_free(base);
  if (const size_t dot = stem.rfind('.'); dot != std::string::npos && dot > 0)
    stem.resize(dot);
  m.name = sanitize(stem);
  switch (raw.channels()) {
  case 1:
    cv::cvtColor(raw, m.bgr, cv::COLOR_GRAY2BGR);
    break;
  case 3:
    m.bgr = raw;
    break;
  case 4:
    cv::cvtColor(raw, m.bgr, cv::COLOR_BGRA2BGR);
    cv::extractChannel(raw, m.alpha, 3);
    m.has_alpha = cv::countNonZero(m.alpha < 255) > 0;
    break;
  default:
    throw Failure("model picture '" + path + "' has " + std::to_string(raw.channels()) +
                  " channels");
  }
  if (!m.has_alpha)
    m.alpha = cv::Mat(m.bgr.size(), CV_8UC1, cv::Scalar(255));
  if (cv::countNonZero(m.alpha >= 128) == 0)
    throw Failure("model picture '" + path + "' is fully transparent");
  outline(m);
  return m;
}

void outline(ModelPicture& m) {
  m.polygon.clear();
  const double w = m.bgr.cols, h = m.bgr.rows;
  if (!m.has_alpha) {
    m.polygon = {{0, 0}, {w, 0}, {w, h}, {0, h}};
    m.principal_points = {{w / 2, h / 2}, {0, 0}, {w, 0}, {w, h}, {0, h}};
  } else {
    // The alpha outline (pixel centres of the boundary), simplified to within a pixel; an
    // alpha in several pieces is outlined by the convex hull of them all.
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(m.alpha >= 128, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    std::vector<cv::Point> hull;
    if (contours.size() == 1) {
      hull = contours[0];
    } else {
      std::vector<cv::Point> all;
      for (const auto& c : contours)
        all.insert(all.end(), c.begin(), c.end());
      cv::convexHull(all, hull);
    }
    std::vector<cv::Point> simple;
    cv::approxPolyDP(hull, simple, 1.0, true);
    for (const cv::Point& p : simple)
      m.polygon.emplace_back(p.x, p.y);
    const cv::Rect box = cv::boundingRect(m.alpha >= 128);
    const double x0 = box.x, y0 = box.y, x1 = box.x + box.width, y1 = box.y + box.height;
    m.principal_points = {{(x0 + x1) / 2, (y0 + y1) / 2}, {x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  }
}

/// A family of look-alike products: the first picture's top `share` of its height (a brand's
/// design) over each further picture in turn, squeezed into the rest. Named first_other; the
/// first picture's outline, alpha and principal points are kept.
std::vector<ModelPicture> make_family(const std::vector<ModelPicture>& pictures, double share) {
  const ModelPicture& design = pictures[0];
  const int top = static_cast<int>(std::lround(share * design.bgr.rows));
  if (top < 1 || top >= design.bgr.rows)
    throw Failure("--family leaves no shared design or no own part of '" + design.name + "'");
  const cv::Rect own(0, top, design.bgr.cols, design.bgr.rows - top);
  std::vector<ModelPicture> family;
  for (size_t i = 1; i < pictures.size(); ++i) {
    ModelPicture product = design;
    product.bgr = design.bgr.clone();
    product.alpha = design.alpha.clone();
    product.name = design.name + "_" + pictures[i].name;
    product.source = pictures[i].source;
    cv::resize(pictures[i].bgr, product.bgr(own), own.size(), 0, 0, cv::INTER_AREA);
    family.push_back(std::move(product));
  }
  return family;
}

ModelPicture elongate(const ModelPicture& m, double aspect) {
  // The same area, the longer side `aspect` times the shorter, along the picture's longer side.
  const double area = static_cast<double>(m.bgr.cols) * m.bgr.rows;
  const int along = static_cast<int>(std::lround(std::sqrt(area * aspect)));
  const int across = std::max(1, static_cast<int>(std::lround(std::sqrt(area / aspect))));
  const cv::Size size =
      m.bgr.cols >= m.bgr.rows ? cv::Size(along, across) : cv::Size(across, along);
  ModelPicture out = m;
  cv::resize(m.bgr, out.bgr, size, 0, 0, cv::INTER_AREA);
  cv::resize(m.alpha, out.alpha, size, 0, 0, cv::INTER_LINEAR);
  if (cv::countNonZero(out.alpha >= 128) == 0)
    throw Failure("--aspect leaves nothing of '" + m.name + "'");
  outline(out);
  return out;
}

ModelPicture make_bundle(const ModelPicture& m, int count) {
  ModelPicture out = m;
  std::vector<cv::Mat> bgr(static_cast<size_t>(count), m.bgr),
      alpha(static_cast<size_t>(count), m.alpha);
  cv::hconcat(bgr, out.bgr);
  cv::hconcat(alpha, out.alpha);
  out.name = m.name + "_bundle" + std::to_string(count);
  outline(out);
  return out;
}

ModelPicture soften(const ModelPicture& m, double factor, double sigma) {
  ModelPicture out = m;
  const cv::Size size(std::max(8, static_cast<int>(std::lround(m.bgr.cols * factor))),
                      std::max(8, static_cast<int>(std::lround(m.bgr.rows * factor))));
  if (size != m.bgr.size()) {
    cv::resize(m.bgr, out.bgr, size, 0, 0, cv::INTER_AREA);
    cv::resize(m.alpha, out.alpha, size, 0, 0, cv::INTER_AREA);
  }
  if (sigma > 0)
    cv::GaussianBlur(out.bgr, out.bgr, cv::Size(0, 0), sigma);
  // Pixel edges map linearly between the two sizes: the same physical points.
  const double sx = static_cast<double>(size.width) / m.bgr.cols,
               sy = static_cast<double>(size.height) / m.bgr.rows;
  for (cv::Point2d& p : out.principal_points)
    p = {p.x * sx, p.y * sy};
  for (cv::Point2d& p : out.polygon)
    p = {p.x * sx, p.y * sy};
  return out;
}

} // namespace synth
