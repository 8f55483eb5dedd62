// SPDX-License-Identifier: LGPL-2.1-or-later
#include <pickdetect/calibration.hpp>

#include <pickdetect/error.hpp>

#include "open_file_storage.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

namespace pickdetect {
namespace {

namespace fs = std::filesystem;

std::string in_quotes(const std::string& path) {
  return "'" + path + "'";
}

/// Undistortion to this precision (normalised image coordinates; 1e-10 is far below a pixel).
const cv::TermCriteria kUndistortCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50,
                                          1e-12);

/// The plane height `height_mm` towards the camera, as a plane z coordinate.
double raised_z(const Calibration& c, double height_mm) {
  const cv::Vec3d centre = -(c.plane_rotation.t() * c.plane_translation);
  return centre[2] >= 0.0 ? height_mm : -height_mm;
}

std::vector<cv::Point2d> to_plane_all(const Calibration& c, const std::vector<cv::Point2d>& pixels,
                                      double height_mm) {
  std::vector<cv::Point2d> out;
  out.reserve(pixels.size());
  if (pixels.empty())
    return out;
  if (c.kind == CalibrationKind::Homography) {
    cv::perspectiveTransform(pixels, out, cv::Matx33d(c.pixel_to_plane));
    return out;
  }
  std::vector<cv::Point2d> normalised;
  cv::undistortPoints(pixels, normalised, c.camera_matrix, c.distortion, cv::noArray(),
                      cv::noArray(), kUndistortCriteria);
  const cv::Matx33d rt = c.plane_rotation.t();
  const cv::Vec3d centre = -(rt * c.plane_translation);
  const double z = raised_z(c, height_mm);
  for (size_t i = 0; i < normalised.size(); i++) {
    const cv::Vec3d ray = rt * cv::Vec3d(normalised[i].x, normalised[i].y, 1.0);
    const double s = (z - centre[2]) / ray[2];
    if (!std::isfinite(s) || s <= 0.0)
      throw Error("pixel (" + std::to_string(pixels[i].x) + ", " + std::to_string(pixels[i].y) +
                  ") does not look onto the work plane");
    out.emplace_back(centre[0] + s * ray[0], centre[1] + s * ray[1]);
  }
  return out;
}

cv::Mat read_matrix(const cv::FileNode& node, const std::string& origin, const char* key, int rows,
                    int cols) {
  if (node.empty())
    throw Error(origin + ": the '" + key + "' key is missing");
  cv::Mat m;
  try {
    node >> m;
  } catch (const cv::Exception& e) {
    throw Error(origin + ": '" + key + "' is not a matrix: " + e.err);
  }
  if (m.empty() || m.rows != rows || m.cols != cols || m.channels() != 1)
    throw Error(origin + ": '" + key + "' must be a " + std::to_string(rows) + "x" +
                std::to_string(cols) + " matrix");
  m.convertTo(m, CV_64F);
  if (!cv::checkRange(m))
    throw Error(origin + ": '" + key + "' holds a value that is not a finite number");
  return m;
}

double read_number(const cv::FileNode& node, double fallback) {
  return node.isReal() || node.isInt() ? static_cast<double>(node) : fallback;
}

double rms(const std::vector<cv::Point2d>& a, const std::vector<cv::Point2d>& b) {
  double sum = 0.0;
  for (size_t i = 0; i < a.size(); i++) {
    const cv::Point2d d = a[i] - b[i];
    sum += d.dot(d);
  }
  return a.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(a.size()));
}

/// Sine of the smallest angle the cloud's spread makes (0: all points on one line).
double spread_ratio(const std::vector<cv::Point2d>& points) {
  cv::Point2d mean(0, 0);
  for (const cv::Point2d& p : points)
    mean += p;
  mean *= 1.0 / static_cast<double>(points.size());
  cv::Matx22d cov = cv::Matx22d::zeros();
  for (const cv::Point2d& p : points) {
    const cv::Vec2d d(p.x - mean.x, p.y - mean.y);
    cov += d * d.t();
  }
  cv::Vec2d eigen;
  cv::eigen(cov, eigen);
  return eigen[0] > 0.0 ? std::sqrt(std::max(0.0, eigen[1]) / eigen[0]) : 0.0;
}

bool collinear(const cv::Point2d& a, const cv::Point2d& b, const cv::Point2d& c) {
  const cv::Point2d u = b - a, v = c - a;
  const double norms = std::hypot(u.x, u.y) * std::hypot(v.x, v.y);
  return norms <= 0.0 || std::abs(u.cross(v)) / norms < 1e-3;
}

/// Refuses point sets that do not fix a plane mapping (`where`: "in the frame", "on the plane").
void check_point_set(const std::vector<cv::Point2d>& points, const char* where) {
  for (size_t i = 0; i < points.size(); i++)
    for (size_t j = 0; j < i; j++)
      if (cv::norm(points[i] - points[j]) < 1e-6)
        throw Error("degenerate point set: points " + std::to_string(j + 1) + " and " +
                    std::to_string(i + 1) + " are the same " + where);
  if (spread_ratio(points) < 1e-3)
    throw Error(std::string("degenerate point set: all the points lie on one line ") + where);
  if (points.size() == static_cast<size_t>(kMinPlanePoints)) {
    for (size_t i = 0; i < 4; i++) {
      const cv::Point2d& a = points[(i + 1) % 4];
      const cv::Point2d& b = points[(i + 2) % 4];
      const cv::Point2d& c = points[(i + 3) % 4];
      if (collinear(a, b, c))
        throw Error(std::string("degenerate point set: of four points, three lie on one line ") +
                    where + " (give a fifth point off that line, or move one)");
    }
  }
}

} // namespace

cv::Point2d Calibration::to_plane(const cv::Point2d& pixel, double height_mm) const {
  return to_plane_all(*this, {pixel}, height_mm)[0];
}

cv::Point2d Calibration::to_pixel(const cv::Point2d& plane_mm, double height_mm) const {
  if (kind == CalibrationKind::Homography) {
    std::vector<cv::Point2d> out;
    cv::perspectiveTransform(std::vector<cv::Point2d>{plane_mm}, out, pixel_to_plane.inv());
    return out[0];
  }
  cv::Vec3d rvec;
  cv::Rodrigues(plane_rotation, rvec);
  std::vector<cv::Point2d> out;
  cv::projectPoints(std::vector<cv::Point3d>{{plane_mm.x, plane_mm.y, raised_z(*this, height_mm)}},
                    rvec, plane_translation, camera_matrix, distortion, out);
  return out[0];
}

Calibration load_calibration(const std::string& path) {
  if (path.empty())
    throw Error("no calibration file given");
  const std::string origin = "calibration file " + in_quotes(path);
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw Error(origin + " does not exist");
  if (!fs::is_regular_file(path, ec))
    throw Error(origin + " is not a regular file");
  if (!std::ifstream(path).good())
    throw Error(origin + " cannot be opened for reading");
  cv::FileStorage store;
  detail::open_for_reading(store, path, origin);
  const cv::FileNode root = store.root();
  if (!root.isMap() || !root["kind"].isString())
    throw Error(origin + ": the 'kind' key (camera-plane or homography) is missing");
  Calibration c;
  const std::string kind = static_cast<std::string>(root["kind"]);
  if (kind == "camera-plane")
    c.kind = CalibrationKind::CameraPlane;
  else if (kind == "homography")
    c.kind = CalibrationKind::Homography;
  else
    throw Error(origin + ": unknown kind '" + kind + "' (camera-plane or homography)");
  if (!root["image_width"].isInt() || !root["image_height"].isInt())
    throw Error(origin + ": 'image_width' and 'image_height' (pixels) are missing");
  c.image_size = {static_cast<int>(root["image_width"]), static_cast<int>(root["image_height"])};
  if (c.image_size.width <= 0 || c.image_size.height <= 0)
    throw Error(origin + ": the image size must be positive");

  if (c.kind == CalibrationKind::CameraPlane) {
    c.camera_matrix =
        cv::Matx33d(read_matrix(root["camera_matrix"], origin, "camera_matrix", 3, 3));
    const cv::Matx33d& k = c.camera_matrix;
    if (!(k(0, 0) > 0.0) || !(k(1, 1) > 0.0) || k(1, 0) != 0.0 || k(2, 0) != 0.0 ||
        k(2, 1) != 0.0 || k(2, 2) != 1.0)
      throw Error(origin + ": 'camera_matrix' must be [fx s cx; 0 fy cy; 0 0 1] with fx, fy > 0");
    const cv::FileNode dn = root["distortion"];
    if (dn.empty())
      throw Error(origin + ": the 'distortion' key is missing");
    cv::Mat d;
    try {
      dn >> d;
    } catch (const cv::Exception& e) {
      throw Error(origin + ": 'distortion' is not a matrix: " + e.err);
    }
    d = d.reshape(1, 1);
    const int n = d.cols;
    if (n != 4 && n != 5 && n != 8 && n != 12 && n != 14)
      throw Error(origin + ": 'distortion' must hold 4, 5, 8, 12 or 14 coefficients, not " +
                  std::to_string(n));
    d.convertTo(d, CV_64F);
    if (!cv::checkRange(d))
      throw Error(origin + ": 'distortion' holds a value that is not a finite number");
    c.distortion.assign(d.begin<double>(), d.end<double>());
    c.plane_rotation =
        cv::Matx33d(read_matrix(root["plane_rotation"], origin, "plane_rotation", 3, 3));
    const cv::Mat t = read_matrix(root["plane_translation"], origin, "plane_translation", 3, 1);
    c.plane_translation = cv::Vec3d(t.at<double>(0), t.at<double>(1), t.at<double>(2));
    const cv::Matx33d should_be_eye = c.plane_rotation.t() * c.plane_rotation;
    if (cv::norm(should_be_eye - cv::Matx33d::eye()) > 1e-6 ||
        std::abs(cv::determinant(c.plane_rotation) - 1.0) > 1e-6)
      throw Error(origin + ": 'plane_rotation' is not a rotation matrix");
    if (std::abs((c.plane_rotation.t() * c.plane_translation)[2]) < 1e-9)
      throw Error(origin + ": the camera lies in the plane ('plane_translation')");
  } else {
    c.pixel_to_plane =
        cv::Matx33d(read_matrix(root["pixel_to_plane"], origin, "pixel_to_plane", 3, 3));
    if (std::abs(cv::determinant(c.pixel_to_plane)) < 1e-15)
      throw Error(origin + ": 'pixel_to_plane' is singular");
  }
  c.reprojection_px = read_number(root["reprojection_error_px"], 0.0);
  c.reprojection_mm = read_number(root["reprojection_error_mm"], 0.0);
  return c;
}

void save_calibration(const Calibration& c, const std::string& path) {
  cv::FileStorage store;
  detail::open_for_writing(store, path, "calibration file " + in_quotes(path));
  const bool camera = c.kind == CalibrationKind::CameraPlane;
  store.writeComment("pickdetect calibration (docs/robot-output.md): plane coordinates in mm, "
                     "origin and axes as the calibration set them");
  store << "kind" << (camera ? "camera-plane" : "homography");
  store << "image_width" << c.image_size.width << "image_height" << c.image_size.height;
  if (camera) {
    store << "camera_matrix" << cv::Mat(c.camera_matrix);
    store << "distortion" << cv::Mat(c.distortion, true).reshape(1, 1);
    store << "plane_rotation" << cv::Mat(c.plane_rotation);
    store << "plane_translation" << cv::Mat(c.plane_translation);
  } else {
    store << "pixel_to_plane" << cv::Mat(c.pixel_to_plane);
  }
  store << "reprojection_error_px" << c.reprojection_px;
  store << "reprojection_error_mm" << c.reprojection_mm;
}

std::vector<cv::Point2f> find_chessboard(const cv::Mat& grey, const cv::Size& inner_corners) {
  std::vector<cv::Point2f> corners;
  if (grey.empty() || grey.type() != CV_8UC1)
    return corners;
  const int flags = cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE;
  if (!cv::findChessboardCorners(grey, inner_corners, corners, flags))
    return {};
  cv::cornerSubPix(grey, corners, cv::Size(5, 5), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 60, 1e-4));
  return corners;
}

Calibration calibrate_chessboard(const std::vector<ChessboardView>& views,
                                 const ChessboardPattern& pattern, size_t plane_view) {
  const std::string pattern_name = std::to_string(pattern.inner_corners.width) + "x" +
                                   std::to_string(pattern.inner_corners.height);
  if (pattern.inner_corners.width < 2 || pattern.inner_corners.height < 2)
    throw Error("the pattern " + pattern_name + " needs at least 2x2 inner corners");
  if (!(pattern.square_mm > 0.0) || !std::isfinite(pattern.square_mm))
    throw Error("the square size must be a positive number of millimetres");
  if (views.size() < static_cast<size_t>(kMinChessboardViews))
    throw Error("too few views: " + std::to_string(views.size()) +
                " chessboard photo(s), at least " + std::to_string(kMinChessboardViews) +
                " are needed (tilted differently)");
  if (plane_view >= views.size())
    throw Error("the plane view is not among the photos");

  std::vector<cv::Point3f> board;
  for (int i = 0; i < pattern.inner_corners.height; i++)
    for (int j = 0; j < pattern.inner_corners.width; j++)
      board.emplace_back(static_cast<float>(j * pattern.square_mm),
                         static_cast<float>(i * pattern.square_mm), 0.f);

  std::vector<std::vector<cv::Point3f>> object_points;
  std::vector<std::vector<cv::Point2f>> image_points;
  const cv::Size size = views[0].grey.size();
  for (const ChessboardView& view : views) {
    if (view.grey.empty() || view.grey.type() != CV_8UC1)
      throw Error("photo " + in_quotes(view.name) + " is not a grey picture");
    if (view.grey.size() != size)
      throw Error("photo " + in_quotes(view.name) + " is " + std::to_string(view.grey.cols) + "x" +
                  std::to_string(view.grey.rows) + ", the first one " + std::to_string(size.width) +
                  "x" + std::to_string(size.height) +
                  ": all photos must come from the camera at one resolution");
    std::vector<cv::Point2f> corners = find_chessboard(view.grey, pattern.inner_corners);
    if (corners.empty())
      throw Error("chessboard pattern " + pattern_name + " (inner corners) not found in " +
                  in_quotes(view.name));
    image_points.push_back(std::move(corners));
    object_points.push_back(board);
  }

  Calibration c;
  c.kind = CalibrationKind::CameraPlane;
  c.image_size = size;
  cv::Mat k, d;
  std::vector<cv::Mat> rvecs, tvecs;
  try {
    // k3 stays 0: with boards that do not reach the corners it only fits noise there.
    c.reprojection_px = cv::calibrateCamera(object_points, image_points, size, k, d, rvecs, tvecs,
                                            cv::CALIB_FIX_K3);
  } catch (const cv::Exception& e) {
    throw Error(std::string("the calibration failed: ") + e.err);
  }
  if (!cv::checkRange(k) || !cv::checkRange(d))
    throw Error("the calibration failed: the views do not fix the camera (tilt the board more)");
  c.camera_matrix = cv::Matx33d(k);
  c.distortion.assign(d.begin<double>(), d.end<double>());
  cv::Mat r;
  cv::Rodrigues(rvecs[plane_view], r);
  c.plane_rotation = cv::Matx33d(r);
  const cv::Mat& t = tvecs[plane_view];
  c.plane_translation = cv::Vec3d(t.at<double>(0), t.at<double>(1), t.at<double>(2));

  std::vector<cv::Point2d> pixels, truth;
  for (size_t i = 0; i < board.size(); i++) {
    pixels.emplace_back(image_points[plane_view][i]);
    truth.emplace_back(board[i].x, board[i].y);
  }
  c.reprojection_mm = rms(to_plane_all(c, pixels, 0.0), truth);
  return c;
}

Calibration calibrate_points(const std::vector<PlanePoint>& points, const cv::Size& image_size,
                             const Calibration* camera) {
  if (points.size() < static_cast<size_t>(kMinPlanePoints))
    throw Error("too few points: " + std::to_string(points.size()) + ", at least " +
                std::to_string(kMinPlanePoints) + " of known plane coordinates are needed");
  if (image_size.width <= 0 || image_size.height <= 0)
    throw Error("the frame size must be positive");
  std::vector<cv::Point2d> pixels, plane;
  for (const PlanePoint& p : points) {
    if (!std::isfinite(p.pixel.x) || !std::isfinite(p.pixel.y) || !std::isfinite(p.plane_mm.x) ||
        !std::isfinite(p.plane_mm.y))
      throw Error("a point's coordinates are not finite numbers");
    pixels.push_back(p.pixel);
    plane.push_back(p.plane_mm);
  }
  check_point_set(pixels, "in the frame");
  check_point_set(plane, "on the plane");

  Calibration c;
  c.image_size = image_size;
  if (!camera || camera->kind != CalibrationKind::CameraPlane) {
    c.kind = CalibrationKind::Homography;
    const cv::Mat h = cv::findHomography(pixels, plane, 0);
    if (h.empty() || !cv::checkRange(h) || std::abs(cv::determinant(h)) < 1e-15)
      throw Error("degenerate point set: no plane mapping fits the points");
    c.pixel_to_plane = cv::Matx33d(h);
  } else {
    if (camera->image_size != image_size)
      throw Error("the camera was calibrated at another frame size");
    c = *camera;
    std::vector<cv::Point3d> object;
    for (const cv::Point2d& p : plane)
      object.emplace_back(p.x, p.y, 0.0);
    cv::Mat rvec, tvec;
    if (!cv::solvePnP(object, pixels, c.camera_matrix, c.distortion, rvec, tvec, false,
                      cv::SOLVEPNP_IPPE))
      throw Error("degenerate point set: the plane's pose cannot be solved from the points");
    cv::solvePnPRefineLM(object, pixels, c.camera_matrix, c.distortion, rvec, tvec);
    cv::Mat r;
    cv::Rodrigues(rvec, r);
    c.plane_rotation = cv::Matx33d(r);
    c.plane_translation = cv::Vec3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  }
  std::vector<cv::Point2d> reprojected;
  for (const cv::Point2d& p : plane)
    reprojected.push_back(c.to_pixel(p));
  c.reprojection_px = rms(reprojected, pixels);
  c.reprojection_mm = rms(to_plane_all(c, pixels, 0.0), plane);
  return c;
}

PlaneInstance locate_on_plane(const Instance& instance, const Calibration& calibration,
                              double height_mm) {
  // The direction of the model picture's x axis at the centre, through the instance's
  // homography (model pixels to frame pixels: perspective included), a short step so that the
  // lens bends it as little as possible; the instance's angle if the homography is singular.
  constexpr double kStepPx = 4.0;
  const cv::Point2d centre(instance.center);
  cv::Point2d ahead;
  const cv::Matx33d& h = instance.homography;
  const cv::Vec3d m0 = h.inv() * cv::Vec3d(centre.x, centre.y, 1.0);
  bool have_direction = false;
  if (std::abs(cv::determinant(h)) > 1e-12 && std::abs(m0[2]) > 1e-12) {
    const cv::Vec3d p0 = h * cv::Vec3d(m0[0] / m0[2], m0[1] / m0[2], 1.0);
    const cv::Vec3d p1 = h * cv::Vec3d(m0[0] / m0[2] + 1.0, m0[1] / m0[2], 1.0);
    const cv::Point2d d(p1[0] / p1[2] - p0[0] / p0[2], p1[1] / p1[2] - p0[1] / p0[2]);
    const double n = std::hypot(d.x, d.y);
    if (std::isfinite(n) && n > 1e-9) {
      ahead = centre + d * (kStepPx / n);
      have_direction = true;
    }
  }
  if (!have_direction) {
    const double radians = instance.angle * CV_PI / 180.0;
    ahead = centre + kStepPx * cv::Point2d(std::cos(radians), std::sin(radians));
  }
  std::vector<cv::Point2d> pixels{centre, ahead, cv::Point2d(instance.grasp)};
  for (const cv::Point2f& p : instance.outline)
    pixels.emplace_back(p);
  const std::vector<cv::Point2d> plane = to_plane_all(calibration, pixels, height_mm);
  PlaneInstance out;
  out.center = plane[0];
  double angle = std::atan2(plane[1].y - plane[0].y, plane[1].x - plane[0].x) * 180.0 / CV_PI;
  if (angle < 0.0)
    angle += 360.0;
  out.angle = angle >= 360.0 ? angle - 360.0 : angle;
  out.grasp = plane[2];
  out.outline.assign(plane.begin() + 3, plane.end());
  return out;
}

cv::Point2d velocity_on_plane(const cv::Point2d& pixel, const cv::Point2d& pixels_per_s,
                              const Calibration& calibration, double height_mm) {
  // One pixel along the motion, mapped: the plane map is smooth at that scale, and the lens
  // bends so short a step as little as anything can.
  const double speed = std::hypot(pixels_per_s.x, pixels_per_s.y);
  if (!std::isfinite(speed) || speed <= 0.0)
    return {0.0, 0.0};
  const cv::Point2d step = pixels_per_s * (1.0 / speed);
  const cv::Point2d from = calibration.to_plane(pixel, height_mm);
  const cv::Point2d to = calibration.to_plane(pixel + step, height_mm);
  return (to - from) * speed;
}

} // namespace pickdetect
