// SPDX-License-Identifier: LGPL-2.1-or-later
// pickdetect-synth: makes annotated scenes (the benchmark's FORMAT.md) or a video clip from
// model pictures: bin heaps and conveyor belts with rotation, small out-of-plane tilt, overlap,
// drop shadows, highlights, lighting gradients, blur, motion blur and sensor noise.
//
//   pickdetect-synth --scenes 20 --out data box.png
//   pickdetect-synth --video belt.avi --scenes 100 --out belt-frames pack.png flyer.png
//   pickdetect-synth --sequence conveyor --speed 25 --scenes 150 --out belt25 pack.png flyer.png
//
// Ground truth is exact with respect to the rendering: each instance is drawn through one
// homography, whose images of the model's principal points and outline are the annotations;
// `covered`, `visible` and `in_frame` are pixel counts of the rendered layers (the instance's
// warped alpha at >= 50%, over a canvas large enough to hold the parts outside the frame).
// Distractor objects lie on the floor under every instance, so they never cover one; --covers
// lays foreign objects (no model's) over instances, and `covered` counts what they hide too.
// The output depends only on the inputs and --seed (own random generator, no std::
// distributions, whose results differ between standard libraries).
//
// Harder scenes, as real totes and pallets are (each off by default): --packed rows of
// identical boxes touching each other, in one or two layers; --aspect for elongated boxes;
// --bundle for a model whose picture repeats a part; --camera for a perspective camera over
// the whole scene; --soft-models for model pictures no sharper than the scenes; --faces for
// products printed on several faces; --glare for specular patches that clip.
//
// Pieces: synth.hpp (types), models.cpp, scene.cpp (floors, placement, rendering), packed.cpp,
// camera.cpp, glare.cpp, sequence.cpp (--sequence: video sequences with a track per object).
#include "synth.hpp"

#include "common/options.hpp"

#include <glib.h>
#include <glib/gstdio.h>
#include <json-glib/json-glib.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

using namespace synth;

void add_points(JsonBuilder* b, const char* key, const std::vector<cv::Point2d>& pts) {
  json_builder_set_member_name(b, key);
  json_builder_begin_array(b);
  for (const cv::Point2d& p : pts) {
    json_builder_begin_array(b);
    json_builder_add_double_value(b, std::round(p.x * 1e4) / 1e4);
    json_builder_add_double_value(b, std::round(p.y * 1e4) / 1e4);
    json_builder_end_array(b);
  }
  json_builder_end_array(b);
}

void add_double(JsonBuilder* b, const char* key, double v) {
  json_builder_set_member_name(b, key);
  json_builder_add_double_value(b, std::round(v * 1e6) / 1e6);
}

std::string join(const std::string& a, const std::string& b) {
  gchar* p = g_build_filename(a.c_str(), b.c_str(), nullptr);
  std::string out(p);
  g_free(p);
  return out;
}

void make_dir(const std::string& dir) {
  if (g_mkdir_with_parents(dir.c_str(), 0755) != 0)
    throw Failure("cannot create folder '" + dir + "'");
}

void write_image(const std::string& path, const cv::Mat& image) {
  if (!cv::imwrite(path, image))
    throw Failure("cannot write '" + path + "'");
}

bool parse_range(const char* text, double& lo, double& hi) {
  if (!text)
    return true;
  char* end = nullptr;
  lo = g_ascii_strtod(text, &end);
  if (end == text)
    return false;
  if (*end == '\0') {
    hi = lo;
    return true;
  }
  if (*end != '-')
    return false;
  const char* second = end + 1;
  hi = g_ascii_strtod(second, &end);
  return end != second && *end == '\0' && lo <= hi;
}

/// Progress on stderr when it is a terminal.
void progress(const char* what, int done, int total) {
  if (!isatty(STDERR_FILENO))
    return;
  std::fprintf(stderr, "\rpickdetect-synth: %s %d/%d%s", what, done, total,
               done == total ? "\n" : "");
  std::fflush(stderr);
}

int run(int argc, char** argv) {
  gint scenes = 10;
  gchar* size = nullptr;
  gchar* instances = nullptr;
  gchar* scale = nullptr;
  gchar* kind = nullptr;
  gchar* out_dir = nullptr;
  gchar* video = nullptr;
  gchar* format = nullptr;
  gchar* name = nullptr;
  gdouble tilt = 8.0;
  gdouble fps = 0.0;
  gchar* sequence = nullptr;
  gdouble speed = 12.0;
  gdouble riders = 0.25;
  gdouble exposure = 0.5;
  gint pick_every = 15;
  gdouble family = 0.0;
  gint64 seed = 1;
  gint distractors = 3;
  gint covers = 0;
  gboolean mixed = FALSE;
  gint packed = 0;
  gdouble aspect = 0.0;
  gint bundle = 0;
  gdouble camera = 0.0;
  gboolean soft = FALSE;
  gint faces = 0;
  gint glare = 0;
  gchar** pictures = nullptr;
  const GOptionEntry entries[] = {
      {"scenes", 'n', 0, G_OPTION_ARG_INT, &scenes, "Scenes (or video frames) to make (10)", "N"},
      {"size", 0, 0, G_OPTION_ARG_STRING, &size, "Frame size (1280x960)", "WxH"},
      {"instances", 0, 0, G_OPTION_ARG_STRING, &instances, "Instances per scene (4-9)", "MIN-MAX"},
      {"scale", 0, 0, G_OPTION_ARG_STRING, &scale, "Scale of the instances (0.9-1.1)", "MIN-MAX"},
      {"tilt", 0, 0, G_OPTION_ARG_DOUBLE, &tilt, "Largest out-of-plane tilt in degrees (8)", "DEG"},
      {"kind", 0, 0, G_OPTION_ARG_STRING, &kind, "bin, conveyor or mixed (mixed)", "KIND"},
      {"mixed-products", 0, 0, G_OPTION_ARG_NONE, &mixed,
       "Mix the models within a scene (default: one model per scene, in turn)", nullptr},
      {"distractors", 0, 0, G_OPTION_ARG_INT, &distractors,
       "Distractor objects on the floor per scene (3)", "N"},
      {"covers", 0, 0, G_OPTION_ARG_INT, &covers,
       "Foreign objects lying on instances per scene (0); they count in 'covered'", "N"},
      {"family", 0, 0, G_OPTION_ARG_DOUBLE, &family,
       "Look-alike products: the first picture's top SHARE of its height (0 < SHARE < 1) is "
       "their common design, each further picture fills the rest of one product",
       "SHARE"},
      {"packed", 0, 0, G_OPTION_ARG_INT, &packed,
       "Packed rows instead of heaps: identical boxes side by side, touching, in LAYERS 1 or 2 "
       "(the second on the seams of the first, covering parts of the boxes below; touching is "
       "not covering); no tilt, one scale per scene, the scale sets how many fit (--instances "
       "unused)",
       "LAYERS"},
      {"aspect", 0, 0, G_OPTION_ARG_DOUBLE, &aspect,
       "Elongated boxes: each model picture resampled to its area at ASPECT:1 (1 < ASPECT <= 5, "
       "long side over short, along its longer side)",
       "ASPECT"},
      {"bundle", 0, 0, G_OPTION_ARG_INT, &bundle,
       "A model that repeats a part: each model picture becomes a bundle of N identical packs "
       "side by side (2 <= N <= 12), named NAME_bundleN",
       "N"},
      {"camera", 0, 0, G_OPTION_ARG_DOUBLE, &camera,
       "Perspective camera DEG off vertical (0 < DEG <= 60), the far side at the top: the whole "
       "scene (floor and instances) is seen through one homography, the truth carried through it",
       "DEG"},
      {"soft-models", 0, 0, G_OPTION_ARG_NONE, &soft,
       "Write model pictures no sharper than the scenes: downsampled by the mean scale (when "
       "below 1) and blurred (sigma 0.8), points and outline scaled with them",
       nullptr},
      {"faces", 0, 0, G_OPTION_ARG_INT, &faces,
       "Products printed on N faces: each N pictures in turn (after --family etc.) are the faces "
       "of one product, one product per scene, each instance shows one face at random",
       "N"},
      {"glare", 0, 0, G_OPTION_ARG_INT, &glare,
       "Specular patches that clip to white, laid on random instances, per scene (0); their own "
       "random stream: the same scenes with or without",
       "N"},
      {"seed", 0, 0, G_OPTION_ARG_INT64, &seed, "Random seed (1)", "N"},
      {"out", 'o', 0, G_OPTION_ARG_FILENAME, &out_dir,
       "Write an annotated dataset here (dataset.json, models/, scenes/)", "DIR"},
      {"format", 0, 0, G_OPTION_ARG_STRING, &format, "Scene pictures: jpg or png (jpg)", "EXT"},
      {"name", 0, 0, G_OPTION_ARG_STRING, &name, "Dataset name (synth-seedN)", "NAME"},
      {"video", 0, 0, G_OPTION_ARG_FILENAME, &video,
       "Write a conveyor clip (MJPEG AVI) instead of independent scenes; with --out its frames "
       "are annotated too",
       "FILE"},
      {"fps", 0, 0, G_OPTION_ARG_DOUBLE, &fps,
       "Frames per second of the clip (10) or the sequence (30)", "FPS"},
      {"sequence", 0, 0, G_OPTION_ARG_STRING, &sequence,
       "Write the frames of one video (FORMAT.md's video sequence: fps, a track per instance): "
       "conveyor (lanes riding right, arrivals from the left) or bin (a still heap whose top "
       "free object is taken away every --pick-every frames); --scenes frames",
       "KIND"},
      {"speed", 0, 0, G_OPTION_ARG_DOUBLE, &speed, "Sequence: belt speed in pixels per frame (12)",
       "PX"},
      {"riders", 0, 0, G_OPTION_ARG_DOUBLE, &riders,
       "Sequence: share of the belt's objects with another lying partly on them and riding "
       "with them (0.25)",
       "SHARE"},
      {"exposure", 0, 0, G_OPTION_ARG_DOUBLE, &exposure,
       "Sequence: share of the frame time the shutter is open: motion blur of speed x SHARE "
       "pixels along the belt (0.5)",
       "SHARE"},
      {"pick-every", 0, 0, G_OPTION_ARG_INT, &pick_every,
       "Bin sequence: the top free object is taken away every N frames (15; 0: never)", "N"},
      {G_OPTION_REMAINING, 0, 0, G_OPTION_ARG_FILENAME_ARRAY, &pictures, nullptr, "PICTURE..."},
      {nullptr, 0, 0, G_OPTION_ARG_NONE, nullptr, nullptr, nullptr}};
  pickdetect::tools::OptionHelp help;
  help.summary = "Makes annotated bin and conveyor scenes (or a conveyor clip) from model "
                 "pictures; a PNG's alpha marks the object.";
  std::string bad_options;
  const bool parsed = pickdetect::tools::parse_options(argc, argv, entries, help, bad_options);
  struct Free {
    std::vector<gchar*> strings;
    gchar** array;
    ~Free() {
      for (gchar* s : strings)
        g_free(s);
      g_strfreev(array);
    }
  } cleanup{{size, instances, scale, kind, out_dir, video, format, name, sequence}, pictures};
  if (!parsed)
    throw Failure(bad_options);
  if (!pictures || !pictures[0])
    throw Failure("give one or more model pictures (see --help)");
  if (!out_dir && !video)
    throw Failure("give --out DIR and/or --video FILE");
  Settings s;
  if (size && std::sscanf(size, "%dx%d", &s.size.width, &s.size.height) != 2)
    throw Failure("--size wants WxH, got '" + std::string(size) + "'");
  if (s.size.width < 64 || s.size.height < 64 || s.size.width > 8192 || s.size.height > 8192)
    throw Failure("--size must lie between 64x64 and 8192x8192");
  double lo = s.min_instances, hi = s.max_instances;
  if (!parse_range(instances, lo, hi) || lo < 0 || hi > 200 || lo != std::floor(lo) ||
      hi != std::floor(hi))
    throw Failure("--instances wants MIN-MAX (whole numbers, at most 200)");
  s.min_instances = static_cast<int>(lo);
  s.max_instances = static_cast<int>(hi);
  if (!parse_range(scale, s.min_scale, s.max_scale) || s.min_scale <= 0.05 || s.max_scale > 10)
    throw Failure("--scale wants MIN-MAX between 0.05 and 10");
  if (tilt < 0 || tilt > 60)
    throw Failure("--tilt must lie between 0 and 60 degrees");
  s.max_tilt = tilt;
  s.kind = kind ? kind : "mixed";
  if (s.kind != "bin" && s.kind != "conveyor" && s.kind != "mixed")
    throw Failure("--kind must be bin, conveyor or mixed");
  if (scenes < 1 || scenes > 100000)
    throw Failure("--scenes must be at least 1");
  s.distractors = std::max(0, distractors);
  if (covers < 0 || covers > 200)
    throw Failure("--covers must lie between 0 and 200");
  s.covers = covers;
  if (packed < 0 || packed > 2)
    throw Failure("--packed wants 1 or 2 layers (0: off)");
  s.packed = packed;
  if (aspect != 0.0 && !(aspect > 1.0 && aspect <= 5.0))
    throw Failure("--aspect must lie above 1 and at most 5");
  if (bundle != 0 && (bundle < 2 || bundle > 12))
    throw Failure("--bundle must lie between 2 and 12");
  if (camera != 0.0 && !(camera > 0.0 && camera <= 60.0))
    throw Failure("--camera must lie above 0 and at most 60 degrees");
  if (faces < 0 || faces > 50)
    throw Failure("--faces must lie between 1 and 50");
  if (glare < 0 || glare > 200)
    throw Failure("--glare must lie between 0 and 200");
  s.glare = glare;
  if (video && (packed || camera != 0.0))
    throw Failure("--packed and --camera make scenes, not a clip");
  SequenceOptions seq;
  if (sequence) {
    seq.kind = sequence;
    if (seq.kind != "conveyor" && seq.kind != "bin")
      throw Failure("--sequence must be conveyor or bin");
    if (video || packed || camera != 0.0)
      throw Failure("--sequence makes its own frames: no --video, --packed or --camera");
    if (!out_dir)
      throw Failure("--sequence wants --out DIR");
    if (!(speed >= 0.0 && speed <= 500.0))
      throw Failure("--speed must lie between 0 and 500 pixels per frame");
    if (!(riders >= 0.0 && riders <= 1.0) || !(exposure >= 0.0 && exposure <= 1.0))
      throw Failure("--riders and --exposure are shares between 0 and 1");
    if (pick_every < 0)
      throw Failure("--pick-every must be 0 or more");
    seq.frames = scenes;
    seq.speed = speed;
    seq.riders = riders;
    seq.exposure = exposure;
    seq.pick_every = pick_every;
  }
  if (fps == 0.0)
    fps = sequence ? 30.0 : 10.0;
  if (!(fps > 0.0 && fps <= 1000.0))
    throw Failure("--fps must lie above 0 and at most 1000");
  const std::string ext = format ? format : "jpg";
  if (ext != "jpg" && ext != "png")
    throw Failure("--format must be jpg or png");

  std::vector<ModelPicture> models;
  for (gchar** p = pictures; *p; ++p) {
    models.push_back(load_model(*p));
    for (size_t i = 0; i + 1 < models.size(); ++i)
      if (models[i].name == models.back().name)
        models.back().name += "_" + std::to_string(models.size());
  }
  if (family != 0.0) {
    if (!(family > 0.0 && family < 1.0))
      throw Failure("--family wants a share of the height between 0 and 1, got " +
                    std::to_string(family));
    if (models.size() < 2)
      throw Failure("--family needs the design picture and at least one more");
    models = make_family(models, family);
  }
  if (aspect != 0.0)
    for (ModelPicture& m : models)
      m = elongate(m, aspect);
  if (bundle != 0)
    for (ModelPicture& m : models)
      m = make_bundle(m, bundle);
  const int products = faces > 1 ? static_cast<int>(models.size()) / faces : 0;
  if (faces > 1 && static_cast<int>(models.size()) % faces != 0)
    throw Failure("--faces " + std::to_string(faces) + " wants the pictures in groups of " +
                  std::to_string(faces) + ", got " + std::to_string(models.size()));
  // With a camera the scene is laid out on the floor it sees, and the margin of the layers'
  // canvas holds the instances the floor's picture puts outside the frame, magnified.
  Camera cam;
  Settings floor_settings = s;
  int margin = margin_for(models, s);
  if (camera != 0.0) {
    cam = tilted_camera(camera, s.size);
    floor_settings.size = cam.floor;
    Settings magnified = s;
    magnified.max_scale *= cam.magnification;
    margin = margin_for(models, magnified) + cam.excess;
  }
  Random rng(static_cast<uint64_t>(seed));
  // The covers draw from their own stream: the same seed gives the same scenes with or
  // without objects lying on them.
  Random cover_rng(static_cast<uint64_t>(seed) ^ 0x9e3779b97f4a7c15ULL);
  cv::theRNG().state = static_cast<uint64_t>(seed) * 2654435761u + 1;
  // The glare too: the same scenes with or without it.
  Random glare_rng(static_cast<uint64_t>(seed) ^ 0x6a09e667f3bcc909ULL);
  const Extras extras{s.covers, &cover_rng, s.glare, &glare_rng};

  std::vector<Rendered> frames;
  std::vector<std::string> kinds;
  if (sequence) {
    frames = make_sequence(models, s, seq, rng, margin, extras,
                           [](int done, int total) { progress("frame", done, total); });
    kinds.assign(frames.size(), seq.kind);
  } else if (video) {
    // One long belt moving right: instances keep their pose and move by `speed` per frame.
    const double speed = s.size.width / 40.0;
    const double length = s.size.width + speed * scenes + 2.0 * margin;
    const int count = std::max(
        1, static_cast<int>(length / s.size.width * (s.min_instances + s.max_instances) / 2.0));
    std::vector<int> all(models.size());
    for (size_t i = 0; i < all.size(); ++i)
      all[i] = static_cast<int>(i);
    std::vector<BeltItem> items;
    for (int i = 0; i < count; ++i) {
      BeltItem it;
      it.model = all[static_cast<size_t>(rng.integer(0, static_cast<int>(all.size()) - 1))];
      it.x = -margin - speed * scenes + rng.uniform(0, length);
      it.y = rng.uniform(0.25, 0.75) * s.size.height;
      draw_look(it, models, s, rng);
      items.push_back(it);
    }
    Random scenery(static_cast<uint64_t>(seed) ^ 0x5eedull);
    cv::Mat belt = background("conveyor", s.size, scenery);
    for (int f = 0; f < scenes; ++f) {
      std::vector<Placed> placed;
      for (const BeltItem& it : items) {
        const double x = it.x + speed * f;
        if (x < -margin || x > s.size.width + margin)
          continue;
        placed.push_back(place_item(models, it, {x, it.y}));
      }
      Rendered r = render(belt.clone(), models, placed, rng, margin, extras);
      drop_off_frame(r);
      frames.push_back(std::move(r));
      kinds.push_back("conveyor");
      progress("frame", f + 1, scenes);
    }
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, s.size, true);
    if (!writer.isOpened())
      throw Failure("cannot write the clip '" + std::string(video) +
                    "' (MJPEG AVI; use a .avi name)");
    for (const Rendered& r : frames)
      writer.write(r.image);
    writer.release();
  } else {
    for (int i = 0; i < scenes; ++i) {
      const std::string k =
          s.kind == "mixed" ? (i % 2 == 0 ? std::string("bin") : std::string("conveyor")) : s.kind;
      std::vector<int> allowed;
      if (mixed)
        for (size_t m = 0; m < models.size(); ++m)
          allowed.push_back(static_cast<int>(m));
      else if (products > 0)
        for (int f = 0; f < faces; ++f)
          allowed.push_back((i % products) * faces + f);
      else
        allowed.push_back(i % static_cast<int>(models.size()));
      cv::Mat bg = background(k, floor_settings.size, rng);
      cv::Mat floor;
      bg.convertTo(floor, CV_8UC3);
      draw_distractors(floor, s.distractors, rng);
      floor.convertTo(bg, CV_32FC3);
      std::vector<Placed> placed = s.packed > 0 ? place_packed(models, allowed, floor_settings, rng)
                                                : place(k, models, allowed, floor_settings, rng);
      if (camera != 0.0) {
        cv::Mat seen;
        cv::warpPerspective(bg, seen, cv::Mat(cam.floor_to_frame), s.size, cv::INTER_LINEAR,
                            cv::BORDER_REPLICATE);
        bg = seen;
        for (Placed& p : placed)
          p.homography = cam.floor_to_frame * p.homography;
      }
      frames.push_back(render(bg, models, placed, rng, margin, extras));
      kinds.push_back(k);
      progress("scene", i + 1, scenes);
    }
  }

  if (!out_dir)
    return 0;
  const std::string dir(out_dir);
  make_dir(join(dir, "models"));
  make_dir(join(dir, "scenes"));
  JsonBuilder* b = json_builder_new();
  json_builder_begin_object(b);
  json_builder_set_member_name(b, "name");
  const std::string dataset_name =
      name ? std::string(name) : "synth-seed" + std::to_string(static_cast<long long>(seed));
  json_builder_add_string_value(b, dataset_name.c_str());
  if (sequence) {
    json_builder_set_member_name(b, "fps");
    json_builder_add_double_value(b, fps);
  }
  json_builder_set_member_name(b, "models");
  json_builder_begin_object(b);
  for (const ModelPicture& sharp : models) {
    // The scenes show the model at about the mean scale (times the camera's at the frame's
    // centre, 1): a soft model is written at that resolution, as one cut from a scene would be.
    const double mean_scale = (s.min_scale + s.max_scale) / 2.0;
    const ModelPicture m = soft ? soften(sharp, std::min(1.0, mean_scale), 0.8) : sharp;
    const std::string file = "models/" + m.name + ".png";
    cv::Mat picture;
    if (m.has_alpha) {
      std::vector<cv::Mat> split;
      cv::split(m.bgr, split);
      split.push_back(m.alpha);
      cv::merge(split, picture);
    } else {
      picture = m.bgr;
    }
    write_image(join(dir, file), picture);
    json_builder_set_member_name(b, m.name.c_str());
    json_builder_begin_object(b);
    json_builder_set_member_name(b, "image");
    json_builder_add_string_value(b, file.c_str());
    add_points(b, "principal_points", m.principal_points);
    add_points(b, "polygon", m.polygon);
    json_builder_end_object(b);
  }
  json_builder_end_object(b);
  json_builder_set_member_name(b, "scenes");
  json_builder_begin_array(b);
  for (size_t i = 0; i < frames.size(); ++i) {
    char file[64];
    std::snprintf(file, sizeof file, "scenes/%04zu.%s", i, ext.c_str());
    if (ext == "jpg")
      cv::imwrite(join(dir, file), frames[i].image, {cv::IMWRITE_JPEG_QUALITY, 92});
    else
      write_image(join(dir, file), frames[i].image);
    json_builder_begin_object(b);
    json_builder_set_member_name(b, "image");
    json_builder_add_string_value(b, file);
    json_builder_set_member_name(b, "kind");
    json_builder_add_string_value(b, kinds[i].c_str());
    json_builder_set_member_name(b, "width");
    json_builder_add_int_value(b, s.size.width);
    json_builder_set_member_name(b, "height");
    json_builder_add_int_value(b, s.size.height);
    json_builder_set_member_name(b, "instances");
    json_builder_begin_array(b);
    for (const Rendered::Truth& t : frames[i].truth) {
      json_builder_begin_object(b);
      json_builder_set_member_name(b, "model");
      json_builder_add_string_value(b, models[static_cast<size_t>(t.model)].name.c_str());
      add_points(b, "points", t.points);
      add_points(b, "polygon", t.polygon);
      add_double(b, "angle", t.angle);
      add_double(b, "scale", t.scale);
      add_double(b, "tilt", t.tilt);
      json_builder_set_member_name(b, "z");
      json_builder_add_int_value(b, t.z);
      add_double(b, "in_frame", t.in_frame);
      add_double(b, "visible", t.visible);
      add_double(b, "covered", t.covered);
      if (t.track >= 0) {
        json_builder_set_member_name(b, "track");
        json_builder_add_int_value(b, t.track);
      }
      json_builder_end_object(b);
    }
    json_builder_end_array(b);
    json_builder_end_object(b);
  }
  json_builder_end_array(b);
  json_builder_end_object(b);
  JsonGenerator* gen = json_generator_new();
  JsonNode* root = json_builder_get_root(b);
  json_generator_set_root(gen, root);
  json_generator_set_pretty(gen, TRUE);
  json_generator_set_indent(gen, 1);
  const std::string json_path = join(dir, "dataset.json");
  GError* error = nullptr;
  const gboolean ok = json_generator_to_file(gen, json_path.c_str(), &error);
  json_node_unref(root);
  g_object_unref(gen);
  g_object_unref(b);
  if (!ok) {
    const std::string message = error->message;
    g_clear_error(&error);
    throw Failure("cannot write '" + json_path + "': " + message);
  }
  std::fprintf(stderr, "pickdetect-synth: wrote %zu scenes to %s\n", frames.size(), dir.c_str());
  return 0;
}

} // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const Failure& e) {
    std::cerr << "pickdetect-synth: " << e.what() << "\n";
    return 1;
  } catch (const cv::Exception& e) {
    std::cerr << "pickdetect-synth: " << e.what() << "\n";
    return 1;
  }
}
