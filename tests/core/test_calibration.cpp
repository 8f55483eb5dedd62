// SPDX-License-Identifier: LGPL-2.1-or-later
// Calibration (issue 19): chessboards rendered through a known camera give it back; points of
// known plane coordinates give the plane; files round-trip; bad input is refused by name.
#include "support/camera_scene.hpp"

#include <pickdetect/calibration.hpp>
#include <pickdetect/error.hpp>

#include <opencv2/imgcodecs.hpp>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

using namespace pickdetect;
namespace cs = pickdetect::camera_scene;
namespace fs = std::filesystem;

fs::path temp_dir() {
  fs::path dir =
      fs::temp_directory_path() / ("pickdetect-calibration-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

/// Views of a 9x6 board of 30 mm squares from around, the first lying flat on the plane.
std::vector<ChessboardView> rendered_views(const Calibration& camera, const ChessboardPattern& p,
                                           std::vector<Calibration>* poses = nullptr) {
  const cv::Mat rays = cs::normalised_rays(camera);
  const cv::Point2d middle(4 * p.square_mm, 2.5 * p.square_mm);
  const double tilts[][2] = {{25, 0},   {35, 20},  {30, -25}, {40, 90},
                             {20, 160}, {35, 200}, {45, -60}, {15, 45}};
  std::vector<ChessboardView> views;
  int i = 0;
  for (const auto& t : tilts) {
    Calibration c = camera;
    cs::look_at(c, middle + cv::Point2d(8.0 * (i % 3) - 8.0, 6.0 * (i % 2) - 3.0), 800.0 + 40.0 * i,
                t[0], t[1]);
    views.push_back({"view" + std::to_string(i), cs::render_chessboard(c, rays, p)});
    if (poses)
      poses->push_back(c);
    i++;
  }
  return views;
}

TEST(Calibration, ChessboardsRenderedThroughAKnownCameraGiveItBack) {
  const Calibration truth = cs::test_camera();
  ChessboardPattern pattern{{9, 6}, 55.0};
  std::vector<Calibration> poses;
  const std::vector<ChessboardView> views = rendered_views(truth, pattern, &poses);
  const Calibration got = calibrate_chessboard(views, pattern, 0);

  EXPECT_LT(got.reprojection_px, 0.3) << "reprojection error " << got.reprojection_px << " px";
  EXPECT_LT(got.reprojection_mm, 0.3) << "plane error " << got.reprojection_mm << " mm";
  for (int k = 0; k < 4; k++) {
    const int r = k < 2 ? k : k - 2, col = k < 2 ? k : 2;
    const double want = truth.camera_matrix(r, col), have = got.camera_matrix(r, col);
    EXPECT_NEAR(have, want, 0.01 * truth.camera_matrix(0, 0))
        << "camera matrix (" << r << ", " << col << "): expected " << want << ", got " << have;
  }
  // The lens: distortion coefficients trade off against each other, so compare what they do:
  // every pixel's ray, out to the frame's corners (focal length and board distances trade off a
  // little: 0.2 % of fx is 1.8 px at the corners).
  std::vector<cv::Point2d> pixels, want, have;
  for (int y = 0; y <= 600; y += 100)
    for (int x = 0; x <= 800; x += 100)
      pixels.emplace_back(x, y);
  cv::undistortPoints(pixels, want, truth.camera_matrix, truth.distortion);
  cv::undistortPoints(pixels, have, got.camera_matrix, got.distortion);
  for (size_t i = 0; i < pixels.size(); i++)
    EXPECT_LT(cv::norm(want[i] - have[i]) * truth.camera_matrix(0, 0), 2.5)
        << "the ray of pixel (" << pixels[i].x << ", " << pixels[i].y << ") is off";
  // The plane of the first view: known plane points map to their pixels and back.
  const Calibration& plane = poses[0];
  for (const cv::Point2d p :
       {cv::Point2d(0, 0), cv::Point2d(240, 0), cv::Point2d(120, 150), cv::Point2d(-20, 160)}) {
    const cv::Point2d pixel = plane.to_pixel(p);
    const cv::Point2d back = got.to_plane(pixel);
    EXPECT_LT(cv::norm(back - p), 0.3) << "plane point (" << p.x << ", " << p.y
                                       << ") mm came back at (" << back.x << ", " << back.y << ")";
    // And 50 mm above the plane, the height the world positions account for.
    const cv::Point2d above = got.to_plane(plane.to_pixel(p, 50.0), 50.0);
    EXPECT_LT(cv::norm(above - p), 0.4) << "raised point (" << p.x << ", " << p.y
                                        << ") came back at (" << above.x << ", " << above.y << ")";
  }
}

TEST(Calibration, ToPlaneInvertsToPixelWithDistortionAndHeight) {
  Calibration c = cs::test_camera();
  cs::look_at(c, {100, 50}, 900, 30, 10);
  for (const double h : {0.0, 25.0, 120.0})
    for (const cv::Point2d p :
         {cv::Point2d(100, 50), cv::Point2d(-250, 300), cv::Point2d(400, -200)}) {
      const cv::Point2d back = c.to_plane(c.to_pixel(p, h), h);
      EXPECT_LT(cv::norm(back - p), 1e-6) << "height " << h << ": (" << p.x << ", " << p.y
                                          << ") came back at (" << back.x << ", " << back.y << ")";
    }
}

TEST(Calibration, PointsOfKnownPlaneCoordinatesGiveTheHomographyOrThePose) {
  Calibration truth = cs::test_camera();
  truth.distortion = {0, 0, 0, 0, 0}; // A homography holds only without lens distortion.
  cs::look_at(truth, {0, 0}, 900, 25, 30);
  std::vector<PlanePoint> points;
  for (const cv::Point2d p : {cv::Point2d(-200, -150), cv::Point2d(220, -140),
                              cv::Point2d(210, 160), cv::Point2d(-190, 170), cv::Point2d(10, 5)})
    points.push_back({truth.to_pixel(p), p});
  const Calibration h = calibrate_points(points, truth.image_size);
  EXPECT_EQ(h.kind, CalibrationKind::Homography);
  EXPECT_LT(h.reprojection_mm, 1e-4);
  const cv::Point2d probe(-77, 93);
  EXPECT_LT(cv::norm(h.to_plane(truth.to_pixel(probe)) - probe), 1e-4);

  Calibration distorted = cs::test_camera();
  cs::look_at(distorted, {0, 0}, 900, 25, 30);
  std::vector<PlanePoint> seen;
  for (const PlanePoint& p : points)
    seen.push_back({distorted.to_pixel(p.plane_mm), p.plane_mm});
  Calibration camera = cs::test_camera(); // Its plane pose is replaced by the points'.
  const Calibration pose = calibrate_points(seen, distorted.image_size, &camera);
  EXPECT_EQ(pose.kind, CalibrationKind::CameraPlane);
  const cv::Point2d raised = pose.to_plane(distorted.to_pixel(probe, 40.0), 40.0);
  EXPECT_LT(cv::norm(raised - probe), 1e-4) << "got (" << raised.x << ", " << raised.y << ")";
}

TEST(Calibration, DegeneratePointSetsAreRefused) {
  const cv::Size size(640, 480);
  auto refused = [&](const std::vector<PlanePoint>& points, const std::string& words) {
    try {
      calibrate_points(points, size);
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
      return;
    }
    ADD_FAILURE() << "accepted a point set that should say '" << words << "'";
  };
  refused({{{0, 0}, {0, 0}}, {{100, 0}, {100, 0}}, {{0, 100}, {0, 100}}}, "too few points");
  refused({{{0, 0}, {0, 0}}, {{100, 0}, {100, 0}}, {{200, 0}, {200, 0}}, {{300, 0}, {300, 0}}},
          "on one line");
  refused({{{0, 0}, {0, 0}}, {{100, 0}, {100, 0}}, {{200, 0}, {200, 0}}, {{0, 100}, {0, 100}}},
          "three lie on one line");
  refused({{{0, 0}, {0, 0}},
           {{100, 0}, {100, 0}},
           {{100, 0}, {100, 0}},
           {{0, 100}, {0, 100}},
           {{90, 80}, {90, 80}}},
          "are the same");
}

TEST(Calibration, FilesRoundTripAndBadFilesAreRefusedByName) {
  const fs::path dir = temp_dir();
  Calibration c = cs::test_camera();
  cs::look_at(c, {10, 20}, 800, 20, 5);
  c.reprojection_px = 0.12;
  const std::string path = (dir / "cell.yml").string();
  save_calibration(c, path);
  const Calibration back = load_calibration(path);
  EXPECT_EQ(back.image_size, c.image_size);
  EXPECT_LT(cv::norm(back.to_plane({123, 456}, 30) - c.to_plane({123, 456}, 30)), 1e-9);
  EXPECT_DOUBLE_EQ(back.reprojection_px, 0.12);

  auto refused = [&](const std::string& file, const std::string& text, const std::string& words) {
    const std::string p = (dir / file).string();
    if (!text.empty())
      std::ofstream(p) << text;
    try {
      load_calibration(p);
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(p), std::string::npos) << "does not name the file: " << what;
      EXPECT_NE(what.find(words), std::string::npos) << what;
      return;
    }
    ADD_FAILURE() << file << " accepted";
  };
  refused("missing.yml", "", "does not exist");
  refused("garbage.yml", "%YAML:1.0\n[[[ not yaml", "not valid");
  refused("nokind.yml", "%YAML:1.0\nimage_width: 640\n", "'kind'");
  refused("badkind.yml", "%YAML:1.0\nkind: stereo\nimage_width: 640\nimage_height: 480\n",
          "unknown kind");
  refused("nomatrix.yml", "%YAML:1.0\nkind: camera-plane\nimage_width: 640\nimage_height: 480\n",
          "'camera_matrix'");
  refused("singular.yml",
          "%YAML:1.0\nkind: homography\nimage_width: 640\nimage_height: 480\npixel_to_plane: "
          "!!opencv-matrix\n"
          "   rows: 3\n   cols: 3\n   dt: d\n   data: [ 0., 0., 0., 0., 0., 0., 0., 0., 0. ]\n",
          "singular");
  fs::remove_all(dir);
}

TEST(Calibration, RefusalsNameThePhotoAndCountTheViews) {
  const Calibration camera = cs::test_camera();
  ChessboardPattern pattern{{9, 6}, 55.0};
  std::vector<ChessboardView> views = rendered_views(camera, pattern);
  try {
    calibrate_chessboard({views[0], views[1]}, pattern);
    ADD_FAILURE() << "two views accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("too few views"), std::string::npos) << e.what();
  }
  views[2].grey.setTo(110); // The board gone from one photo.
  views[2].name = "empty-table.png";
  try {
    calibrate_chessboard(views, pattern);
    ADD_FAILURE() << "a photo with no board accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not found in 'empty-table.png'"), std::string::npos)
        << e.what();
  }
}

#ifdef PICKDETECT_CALIBRATE_TOOL
/// Runs the tool; its exit status, and what it printed in `output`.
int run_tool(const std::string& args, std::string& output) {
  const std::string command = std::string(PICKDETECT_CALIBRATE_TOOL) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe)
    return -1;
  char buffer[512];
  while (fgets(buffer, sizeof buffer, pipe))
    output += buffer;
  const int status = pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(CalibrateTool, OpenCvSampleChessboardsCalibrateAndAPictureWithNoBoardIsNamed) {
  const fs::path dir = temp_dir();
  const std::string data = PICKDETECT_TEST_DATA;
  std::string pictures;
  for (const char* n :
       {"01", "02", "03", "04", "05", "06", "07", "08", "09", "11", "12", "13", "14"})
    pictures += " " + data + "/left" + n + ".jpg";
  const std::string out = (dir / "cell.yml").string();
  std::string output;
  ASSERT_EQ(run_tool("--pattern 9x6 --square 25 -o " + out + pictures, output), 0) << output;
  EXPECT_NE(output.find(" px (RMS)"), std::string::npos) << output;
  EXPECT_NE(output.find(" mm (RMS"), std::string::npos) << output;
  const Calibration c = load_calibration(out);
  EXPECT_EQ(c.image_size, cv::Size(640, 480));
  EXPECT_LT(c.reprojection_px, 0.5) << "OpenCV's own sample boards";
  // The first corner of the plane picture is the origin, the next one 25 mm along x.
  const cv::Mat grey = cv::imread(data + "/left01.jpg", cv::IMREAD_GRAYSCALE);
  const std::vector<cv::Point2f> corners = find_chessboard(grey, {9, 6});
  ASSERT_EQ(corners.size(), 54u);
  EXPECT_LT(cv::norm(c.to_plane(corners[0]) - cv::Point2d(0, 0)), 0.5);
  EXPECT_LT(cv::norm(c.to_plane(corners[1]) - cv::Point2d(25, 0)), 0.5);
  EXPECT_LT(cv::norm(c.to_plane(corners[9]) - cv::Point2d(0, 25)), 0.5);

  const std::string blank = (dir / "no-board.png").string();
  cv::imwrite(blank, cv::Mat(480, 640, CV_8UC1, cv::Scalar(128)));
  output.clear();
  EXPECT_EQ(run_tool("--pattern 9x6 --square 25 -o " + out + pictures + " " + blank, output), 1);
  EXPECT_NE(output.find("not found in '" + blank + "'"), std::string::npos) << output;
  output.clear();
  EXPECT_EQ(run_tool("--pattern 9x6 --square 25 -o " + out + " " + data + "/left01.jpg", output),
            1);
  EXPECT_NE(output.find("too few views"), std::string::npos) << output;

  std::ofstream(dir / "points.txt")
      << "# u v x y\n10 10 0 0\n100 10 90 0\n200 10 190 0\n300 10 290 0\n";
  output.clear();
  EXPECT_EQ(
      run_tool("--points " + (dir / "points.txt").string() + " --size 640x480 -o " + out, output),
      1);
  EXPECT_NE(output.find("degenerate point set"), std::string::npos) << output;
  std::ofstream(dir / "points.txt")
      << "10 10 0 0\n600 12 590 0\n590 470 590 460\n15 460 0 460\n300 240 290 230\n";
  output.clear();
  EXPECT_EQ(
      run_tool("--points " + (dir / "points.txt").string() + " --size 640x480 -o " + out, output),
      0)
      << output;
  EXPECT_EQ(load_calibration(out).kind, CalibrationKind::Homography);
  fs::remove_all(dir);
}
#endif

} // namespace
