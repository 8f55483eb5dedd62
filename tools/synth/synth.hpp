// SPDX-License-Identifier: LGPL-2.1-or-later
// pickdetect-synth's pieces: the random generator, model pictures, placements and rendering.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace synth {

class Failure : public std::runtime_error {
public:
  explicit Failure(const std::string& what) : std::runtime_error(what) {}
};

/// SplitMix64: small, fast, and the same everywhere.
class Random {
public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [a, b).
  double uniform(double a, double b) {
    return a + (b - a) * static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0);
  }
  /// Uniform integer in [a, b].
  int integer(int a, int b) {
    return a + static_cast<int>(next() % static_cast<uint64_t>(b - a + 1));
  }
  bool chance(double p) { return uniform(0.0, 1.0) < p; }
  /// Normal (Box-Muller).
  double normal(double mean, double sigma) {
    const double u1 = uniform(1e-12, 1.0), u2 = uniform(0.0, 1.0);
    return mean + sigma * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * CV_PI * u2);
  }

private:
  uint64_t state_;
};

struct ModelPicture {
  std::string name;
  std::string source;
  cv::Mat bgr;   ///< CV_8UC3.
  cv::Mat alpha; ///< CV_8UC1.
  bool has_alpha = false;
  std::vector<cv::Point2d> principal_points;
  std::vector<cv::Point2d> polygon;
};

struct Placed {
  int model = 0;
  int level = -1;         ///< Stacking level (--packed: 0 the floor layer, 1 on it); -1: own z.
  int track = -1;         ///< Identity of the object in a sequence (--sequence); -1: none.
  cv::Matx33d homography; ///< Model pixels -> frame pixels.
  double angle = 0, scale = 1, tilt = 0;
  double brightness = 1.0;
  bool highlight = false;
  cv::Point2d highlight_at; ///< Model pixels.
};

struct Rendered {
  cv::Mat image;
  struct Truth {
    int model = 0;
    std::vector<cv::Point2d> points, polygon;
    double angle = 0, scale = 1, tilt = 0, in_frame = 0, visible = 0, covered = 0;
    int z = 0;
    int track = -1; ///< Placed::track.
  };
  std::vector<Truth> truth;
};

struct Settings {
  cv::Size size{1280, 960};
  int min_instances = 4, max_instances = 9;
  double min_scale = 0.9, max_scale = 1.1;
  double max_tilt = 8.0;
  bool mixed = false;
  std::string kind = "mixed";
  int distractors = 3;
  int covers = 0; ///< Foreign objects lying on instances, per scene.
  int packed = 0; ///< Layers of packed rows (0: heaps and belts as ever).
  int glare = 0;  ///< Specular patches per scene.
};

/// What render() lays over the instances besides themselves, each from its own random stream.
struct Extras {
  int covers = 0;
  Random* cover_rng = nullptr;
  int glare = 0;
  Random* glare_rng = nullptr;
  /// No random motion blur (a sequence blurs along its belt itself); the random draws are the
  /// same, so the rest of the look does not change.
  bool fixed_blur = false;
};

/// What --sequence makes (sequence.cpp).
struct SequenceOptions {
  std::string kind = "conveyor"; ///< "conveyor" or "bin".
  int frames = 150;
  double speed = 12.0;   ///< Conveyor: pixels per frame.
  double riders = 0.25;  ///< Conveyor: share of objects with another lying partly on them.
  double gap = 200.0;    ///< Conveyor: largest extra gap between objects of a lane, pixels.
  double exposure = 0.5; ///< Conveyor: share of the frame time the shutter is open (blur).
  int pick_every = 15;   ///< Bin: the top free object is taken away every N frames (0: never).
};

// models.cpp: model pictures and what the options make of them.
ModelPicture load_model(const std::string& path);
/// The outline and principal points of a picture from its alpha (or its frame without one).
void outline(ModelPicture& m);
std::vector<ModelPicture> make_family(const std::vector<ModelPicture>& pictures, double share);
ModelPicture elongate(const ModelPicture& m, double aspect);
ModelPicture make_bundle(const ModelPicture& m, int count);
ModelPicture soften(const ModelPicture& m, double factor, double sigma);

// scene.cpp: floors, placements and the rendering with its ground truth.
cv::Matx33d placement(const ModelPicture& m, double angle, double scale, double tilt,
                      double tilt_axis, cv::Point2d at);
std::vector<cv::Point2d> apply(const cv::Matx33d& h, const std::vector<cv::Point2d>& pts);
cv::Mat background(const std::string& kind, cv::Size size, Random& rng);
void draw_distractors(cv::Mat& bg, int count, Random& rng);
Rendered render(cv::Mat bg, const std::vector<ModelPicture>& models,
                const std::vector<Placed>& placed, Random& rng, int margin, const Extras& extras);
std::vector<Placed> place(const std::string& kind, const std::vector<ModelPicture>& models,
                          const std::vector<int>& allowed, const Settings& s, Random& rng);
int margin_for(const std::vector<ModelPicture>& models, const Settings& s);

// sequence.cpp: the frames of one video, each instance with its `track`.
/// An object on a belt: drawn once, placed again in every frame at its centre moved along the
/// belt (--video's clip and the conveyor sequence).
struct BeltItem {
  int model = 0;
  int track = -1;      ///< Placed::track.
  double x = 0, y = 0; ///< Centre at frame 0 (belt coordinates).
  double angle = 0, scale = 1, tilt = 0, axis = 0, brightness = 1;
  bool highlight = false;
  cv::Point2d highlight_at; ///< Model pixels.
  bool rider = false;       ///< Lies on another item (drawn after every item that is not one).
};
/// Draws `it`'s angle, scale, tilt, axis, brightness and highlight from `rng`, in that order,
/// for its model (`it.model` set already).
void draw_look(BeltItem& it, const std::vector<ModelPicture>& models, const Settings& s,
               Random& rng);
/// `it` placed with its centre at `at` (frame pixels).
Placed place_item(const std::vector<ModelPicture>& models, const BeltItem& it, cv::Point2d at);
/// Drops from `r`'s ground truth the instances wholly off the frame: they are not part of it.
void drop_off_frame(Rendered& r);
std::vector<Rendered> make_sequence(const std::vector<ModelPicture>& models, const Settings& s,
                                    const SequenceOptions& o, Random& rng, int margin,
                                    const Extras& extras, void (*progress)(int done, int total));

// packed.cpp: rows of identical boxes side by side, in one or two layers.
std::vector<Placed> place_packed(const std::vector<ModelPicture>& models,
                                 const std::vector<int>& allowed, const Settings& s, Random& rng);

// glare.cpp: specular patches that clip.
void add_glare(cv::Mat& frame, const std::vector<ModelPicture>& models,
               const std::vector<Placed>& placed, int count, Random& rng);

// camera.cpp: a camera tilted off vertical over the whole floor.
struct Camera {
  cv::Matx33d floor_to_frame = cv::Matx33d::eye(); ///< Floor pixels -> frame pixels.
  cv::Size floor;             ///< The floor's picture: every floor point the frame sees.
  double magnification = 1.0; ///< Largest scale of floor_to_frame over the floor.
  int excess = 0; ///< How far the floor's picture reaches outside the frame, in frame pixels.
};
Camera tilted_camera(double degrees, cv::Size frame);

} // namespace synth
