// SPDX-License-Identifier: LGPL-2.1-or-later
// From frame pixels to millimetres on the work plane: the camera (intrinsics, lens distortion)
// and the plane's pose, from chessboard photos or from points of known plane coordinates, and
// the mapping of an instance onto the plane.
//
// Plane coordinates: millimetres, x and y in the plane, z = 0 on it. From a chessboard lying on
// the plane, the origin is the pattern's first inner corner (the first corner
// cv::findChessboardCorners gives), x runs along the pattern's rows (first corner to second),
// y from the first row of inner corners to the second. Heights are measured from the plane
// towards the camera. Angles on the plane are in degrees in [0, 360), from the plane's x axis
// towards its y axis.
#pragma once

#include <pickdetect/export.hpp>

#include <pickdetect/detector.hpp>

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace pickdetect {

/// What a calibration knows about the camera.
enum class CalibrationKind {
  /// Camera matrix, lens distortion and the plane's pose: points are undistorted and objects'
  /// heights are accounted for (a ray from the camera meets the plane raised to that height).
  CameraPlane,
  /// A homography from frame pixels to plane millimetres only (from points of known plane
  /// coordinates, no lens model): no distortion correction, and heights cannot be accounted for.
  Homography,
};

/// A calibrated cell: the camera looking at the work plane. A plain value; load_calibration()
/// and save_calibration() read and write it.
struct PICKDETECT_API Calibration {
  CalibrationKind kind = CalibrationKind::CameraPlane;
  cv::Size image_size; ///< Frame size the calibration holds for, in pixels.
  // ---- CameraPlane ----
  cv::Matx33d camera_matrix = cv::Matx33d::eye(); ///< fx, fy, cx, cy in pixels.
  /// OpenCV's distortion coefficients (k1, k2, p1, p2[, k3[, k4, k5, k6]]).
  std::vector<double> distortion;
  /// Plane to camera: X_camera = plane_rotation * X_plane + plane_translation (millimetres).
  cv::Matx33d plane_rotation = cv::Matx33d::eye();
  cv::Vec3d plane_translation{0.0, 0.0, 1.0};
  // ---- Homography ----
  cv::Matx33d pixel_to_plane = cv::Matx33d::eye(); ///< Frame pixels to plane millimetres.
  // ---- How well it fits (written by the calibration, informative) ----
  double reprojection_px = 0.0; ///< RMS reprojection error in pixels.
  double reprojection_mm = 0.0; ///< RMS error of the plane's points mapped back, in mm.

  /// The point of the plane raised by `height_mm` (towards the camera) that the frame pixel
  /// shows. `height_mm` is ignored by a Homography calibration. Throws Error when the pixel's
  /// ray does not meet that plane in front of the camera (a pixel above the horizon).
  cv::Point2d to_plane(const cv::Point2d& pixel, double height_mm = 0.0) const;

  /// Where the plane point (raised by `height_mm`) appears in the frame, lens distortion
  /// included: the inverse of to_plane().
  cv::Point2d to_pixel(const cv::Point2d& plane_mm, double height_mm = 0.0) const;
};

/// Reads a calibration file (YAML written by save_calibration() or pickdetect-calibrate).
/// Throws Error naming the file and what was wrong.
PICKDETECT_API Calibration load_calibration(const std::string& path);

/// Writes a calibration file (YAML through cv::FileStorage). Throws Error when it cannot.
PICKDETECT_API void save_calibration(const Calibration& calibration, const std::string& path);

/// A chessboard: inner corners per row (width) and per column (height), square side in mm.
struct ChessboardPattern {
  cv::Size inner_corners{9, 6};
  double square_mm = 25.0;
};

/// One photo of the chessboard; `name` (its file) names it in refusals.
struct ChessboardView {
  std::string name;
  cv::Mat grey; ///< CV_8UC1.
};

/// Fewest chessboard photos calibrate_chessboard() accepts.
constexpr int kMinChessboardViews = 3;

/// The inner corners of the pattern in the photo, refined to subpixel; empty when not found.
PICKDETECT_API std::vector<cv::Point2f> find_chessboard(const cv::Mat& grey,
                                                        const cv::Size& inner_corners);

/// Camera matrix and distortion from every view, the plane's pose from views[plane_view] (the
/// photo of the pattern lying on the work plane). Throws Error when there are fewer than
/// kMinChessboardViews views, when the pattern is not found in one (naming it), or when the
/// views differ in size.
PICKDETECT_API Calibration calibrate_chessboard(const std::vector<ChessboardView>& views,
                                                const ChessboardPattern& pattern,
                                                size_t plane_view = 0);

/// A point whose place is known both in the frame (pixels) and on the plane (mm).
struct PlanePoint {
  cv::Point2d pixel;
  cv::Point2d plane_mm;
};

/// Fewest points calibrate_points() accepts.
constexpr int kMinPlanePoints = 4;

/// The plane from four or more points of known plane coordinates. With `camera` (a
/// CameraPlane calibration whose intrinsics are used; its plane pose is replaced) the plane's
/// pose is solved and the result is a CameraPlane calibration; without, a Homography one of
/// `image_size`. Throws Error for fewer than kMinPlanePoints points or a degenerate set (points
/// repeated, three or more of them all on one line, in the frame or on the plane).
PICKDETECT_API Calibration calibrate_points(const std::vector<PlanePoint>& points,
                                            const cv::Size& image_size,
                                            const Calibration* camera = nullptr);

/// An instance's place on the plane, in millimetres.
struct PlaneInstance {
  cv::Point2d center;
  double angle = 0.0; ///< Degrees in [0, 360), from the plane's x axis towards its y axis.
  cv::Point2d grasp;
  std::vector<cv::Point2d> outline;
  /// With tracking, the motion on the plane in millimetres per second (velocity_on_plane); 0
  /// otherwise.
  cv::Point2d velocity;
};

/// The instance's centre, grasp point, outline and angle on the plane, its top face lying
/// `height_mm` above it (the model's height). Throws Error as Calibration::to_plane().
PICKDETECT_API PlaneInstance locate_on_plane(const Instance& instance,
                                             const Calibration& calibration,
                                             double height_mm = 0.0);

/// A motion of `pixels_per_s` (frame pixels per second) at `pixel` as millimetres per second on
/// the plane raised by `height_mm`: the plane map's local change along the motion. Throws Error
/// as Calibration::to_plane().
PICKDETECT_API cv::Point2d velocity_on_plane(const cv::Point2d& pixel,
                                             const cv::Point2d& pixels_per_s,
                                             const Calibration& calibration,
                                             double height_mm = 0.0);

} // namespace pickdetect
