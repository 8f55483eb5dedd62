// SPDX-License-Identifier: LGPL-2.1-or-later
// pickdetect-calibrate: writes the calibration file the pickdetect element's `calibration`
// property reads (docs/robot-output.md).
//
//   pickdetect-calibrate --pattern 9x6 --square 25 [--plane PICTURE] -o cell.yml PICTURES...
//       camera matrix and lens distortion from every chessboard photo; the work plane's pose
//       from the photo of the pattern lying on it (--plane, default the first picture): origin
//       at the pattern's first inner corner, x along its rows.
//   pickdetect-calibrate --points POINTS [--size WxH] -o cell.yml [--pattern ... PICTURES...]
//       the plane from four or more points of known plane coordinates, one "u v x y" line each
//       (pixel column and row, plane x and y in mm; '#' starts a comment). With chessboard
//       photos the camera comes from them and the plane's pose is solved from the points;
//       without, a plain homography of frames of --size (no lens model, no heights).
//
// Prints the reprojection error in pixels and in millimetres. Exit status 1 on a refusal (the
// pattern not found, naming the photo; too few views; a degenerate point set), 2 on bad usage.
#include "common/options.hpp"

#include <pickdetect/calibration.hpp>
#include <pickdetect/error.hpp>

#include <opencv2/imgcodecs.hpp>

#include <glib.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace {

bool parse_size(const char* text, cv::Size& size) {
  int w = 0, h = 0;
  char x = 0, rest = 0;
  if (std::sscanf(text, "%d%c%d%c", &w, &x, &h, &rest) != 3 || (x != 'x' && x != 'X') || w <= 0 ||
      h <= 0)
    return false;
  size = {w, h};
  return true;
}

std::vector<pickdetect::PlanePoint> read_points(const std::string& path) {
  std::ifstream in(path);
  if (!in)
    throw pickdetect::Error("points file '" + path + "' cannot be opened");
  std::vector<pickdetect::PlanePoint> points;
  std::string line;
  for (int number = 1; std::getline(in, line); number++) {
    line = line.substr(0, line.find('#'));
    std::istringstream fields(line);
    pickdetect::PlanePoint p;
    std::string extra;
    if (!(fields >> std::ws) || fields.eof())
      continue; // A blank or comment line.
    if (!(fields >> p.pixel.x >> p.pixel.y >> p.plane_mm.x >> p.plane_mm.y) || (fields >> extra))
      throw pickdetect::Error("points file '" + path + "', line " + std::to_string(number) +
                              ": expected four numbers, pixel u v and plane x y (mm)");
    points.push_back(p);
  }
  return points;
}

pickdetect::ChessboardView read_view(const std::string& path) {
  cv::Mat grey = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (grey.empty())
    throw pickdetect::Error("photo '" + path + "' cannot be read as a picture");
  return {path, grey};
}

} // namespace

int main(int argc, char** argv) {
  gchar* pattern_text = nullptr;
  gdouble square = 0.0;
  gchar* plane = nullptr;
  gchar* output = nullptr;
  gchar* points_path = nullptr;
  gchar* size_text = nullptr;
  const GOptionEntry entries[] = {
      {"pattern", 'p', 0, G_OPTION_ARG_STRING, &pattern_text,
       "Chessboard inner corners per row x per column, e.g. 9x6", "WxH"},
      {"square", 's', 0, G_OPTION_ARG_DOUBLE, &square, "Side of a chessboard square in mm", "MM"},
      {"plane", 0, 0, G_OPTION_ARG_FILENAME, &plane,
       "Photo of the chessboard lying on the work plane (default: the first picture)", "PICTURE"},
      {"points", 0, 0, G_OPTION_ARG_FILENAME, &points_path,
       "Plane from points of known plane coordinates: lines 'u v x y' (pixels, mm)", "FILE"},
      {"size", 0, 0, G_OPTION_ARG_STRING, &size_text,
       "Frame size for --points without chessboard photos", "WxH"},
      {"output", 'o', 0, G_OPTION_ARG_FILENAME, &output, "Calibration file to write (YAML)",
       "FILE"},
      {nullptr, 0, 0, G_OPTION_ARG_NONE, nullptr, nullptr, nullptr}};
  pickdetect::tools::OptionHelp help;
  help.parameter = "[PICTURES...] - calibrate the camera and the work plane";
  help.description = "Plane coordinates: mm; from a chessboard, origin at the pattern's first "
                     "inner corner, x along its rows, y from its first row to the next; heights "
                     "towards the camera. See docs/robot-output.md.";
  std::string bad_options;
  if (!pickdetect::tools::parse_options(argc, argv, entries, help, bad_options)) {
    std::fprintf(stderr, "pickdetect-calibrate: %s\n", bad_options.c_str());
    return 2;
  }
  auto cleanup = [&] {
    g_free(pattern_text);
    g_free(plane);
    g_free(output);
    g_free(points_path);
    g_free(size_text);
  };
  auto usage = [&](const char* message) {
    std::fprintf(stderr, "pickdetect-calibrate: %s (see --help)\n", message);
    cleanup();
    return 2;
  };

  std::vector<std::string> pictures(argv + 1, argv + argc);
  if (!output)
    return usage("give the calibration file to write with -o FILE");
  if (pictures.empty() && !points_path && !plane)
    return usage("give chessboard photos, or --points FILE");
  pickdetect::ChessboardPattern pattern;
  const bool chessboard = !pictures.empty() || plane;
  if (chessboard) {
    if (!pattern_text || !parse_size(pattern_text, pattern.inner_corners))
      return usage("give the chessboard's inner corners with --pattern WxH, e.g. 9x6");
    if (!(square > 0.0))
      return usage("give the side of a chessboard square in mm with --square MM");
    pattern.square_mm = square;
  }
  cv::Size size;
  if (size_text && !parse_size(size_text, size))
    return usage("--size must be WxH in pixels, e.g. 1280x960");
  if (points_path && !chessboard && !size_text)
    return usage("--points without chessboard photos needs the frame size, --size WxH");

  int status = 0;
  try {
    pickdetect::Calibration calibration;
    if (chessboard) {
      std::vector<pickdetect::ChessboardView> views;
      size_t plane_view = 0;
      if (plane) {
        const auto it = std::find(pictures.begin(), pictures.end(), std::string(plane));
        if (it == pictures.end())
          pictures.insert(pictures.begin(), plane); // The plane photo is a view too.
        else
          plane_view = static_cast<size_t>(it - pictures.begin());
      }
      for (const std::string& p : pictures)
        views.push_back(read_view(p));
      calibration = pickdetect::calibrate_chessboard(views, pattern, plane_view);
      std::printf("camera: fx %.2f fy %.2f cx %.2f cy %.2f px; distortion",
                  calibration.camera_matrix(0, 0), calibration.camera_matrix(1, 1),
                  calibration.camera_matrix(0, 2), calibration.camera_matrix(1, 2));
      for (const double d : calibration.distortion)
        std::printf(" %.5f", d);
      std::printf("\nchessboard: %zu views, reprojection error %.3f px (RMS); plane from '%s': "
                  "%.3f mm (RMS, its corners mapped back onto the plane)\n",
                  views.size(), calibration.reprojection_px, views[plane_view].name.c_str(),
                  calibration.reprojection_mm);
    }
    if (points_path) {
      const std::vector<pickdetect::PlanePoint> points = read_points(points_path);
      if (size_text && chessboard && size != calibration.image_size)
        throw pickdetect::Error("--size differs from the chessboard photos' size");
      calibration = pickdetect::calibrate_points(points, chessboard ? calibration.image_size : size,
                                                 chessboard ? &calibration : nullptr);
      std::printf("points: %zu from '%s', %s; reprojection error %.3f px, %.3f mm (RMS)\n",
                  points.size(), points_path,
                  chessboard ? "plane pose solved with the chessboard's camera"
                             : "homography (no lens model, heights not accounted for)",
                  calibration.reprojection_px, calibration.reprojection_mm);
    }
    pickdetect::save_calibration(calibration, output);
    std::printf("wrote %s (%dx%d frames)\n", output, calibration.image_size.width,
                calibration.image_size.height);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pickdetect-calibrate: %s\n", e.what());
    status = 1;
  }
  cleanup();
  return status;
}
