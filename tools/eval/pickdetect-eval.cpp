// SPDX-License-Identifier: LGPL-2.1-or-later
// pickdetect-eval: measures the pickdetect element's accuracy on an annotated dataset.
//
//   pickdetect-eval DATASET_DIR
//   pickdetect-eval --method voting --json --detections-out voting.jsonl DATASET_DIR
//   pickdetect-eval --score detections.jsonl DATASET_DIR     (scores a file, runs nothing)
//   pickdetect-eval --frame-scale 0.5 DATASET_DIR   (frames and truth shrunk: 1280x960 -> 640x480)
//   pickdetect-eval --frame-gain 0.3 DATASET_DIR    (frames taken with 30 % of the light)
//
// Every scene goes through the real element (appsrc ! pickdetect ! appsink) once per method,
// with all the dataset's models loaded at once as a user would (or, with --per-model, once per
// model with that model alone), and the instances are read back from the buffers' metadata. The
// plugin is found through GST_PLUGIN_PATH; a binary run from its build tree also looks in the build
// tree's gst/ folder first.
#include "dataset.hpp"
#include "metrics.hpp"
#include "runner.hpp"

#include "common/options.hpp"
#include "common/plugin-path.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <glib/gstdio.h>
#include <gst/gst.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <unistd.h>

using namespace pickdetect::eval;

namespace {

const char* const kMethods[] = {"voting", "ransac-clustered", "ransac-all"};

class Progress {
public:
  explicit Progress(size_t total) : total_(total), tty_(isatty(STDERR_FILENO) == 1) {}

  void step(const std::string& label) {
    ++done_;
    if (tty_) {
      const int width = 30;
      const int filled = static_cast<int>(width * done_ / (total_ ? total_ : 1));
      std::fprintf(stderr, "\r[%s%s] %zu/%zu %-40.40s", std::string(filled, '#').c_str(),
                   std::string(width - filled, '.').c_str(), done_, total_, label.c_str());
      if (done_ == total_)
        std::fprintf(stderr, "\n");
    } else if (label != last_) {
      std::fprintf(stderr, "pickdetect-eval: %s (%zu/%zu frames)\n", label.c_str(), done_, total_);
    }
    last_ = label;
    std::fflush(stderr);
  }

  void abort() {
    if (tty_ && done_ > 0 && done_ < total_)
      std::fprintf(stderr, "\n");
  }

private:
  size_t total_;
  size_t done_ = 0;
  bool tty_;
  std::string last_;
};

struct Options {
  gchar* method = nullptr;
  gchar* detections_out = nullptr;
  gchar* score = nullptr;
  gboolean json = FALSE;
  gboolean bgr = FALSE;
  gboolean per_model = FALSE;
  gdouble frame_scale = 1.0;
  gdouble frame_gain = 1.0;
  gdouble frame_contrast = 1.0;
  gchar* models = nullptr;
  gchar* ratio = nullptr;
  gchar* bandwidth = nullptr;
  gchar* min_matches = nullptr;
  gchar* allow_scale = nullptr;
  gchar* max_instances = nullptr;
  gchar** set = nullptr;
  gchar** rest = nullptr;

  ~Options() {
    g_free(method);
    g_free(detections_out);
    g_free(score);
    g_free(models);
    g_free(ratio);
    g_free(bandwidth);
    g_free(min_matches);
    g_free(allow_scale);
    g_free(max_instances);
    g_strfreev(set);
    g_strfreev(rest);
  }
};

/// Resizes every frame by `scale` (area interpolation) and carries the dataset's truth with it:
/// pixel centres aligned as cv::resize does, x' = (x + 0.5) * fx - 0.5 with fx = new width /
/// old width (and alike in y), sizes rounded to whole pixels.
void scale_frames(Dataset& dataset, std::vector<Frame>* frames, double scale) {
  for (size_t i = 0; i < dataset.scenes.size(); ++i) {
    Scene& scene = dataset.scenes[i];
    const int width = std::max(1, static_cast<int>(std::lround(scene.width * scale)));
    const int height = std::max(1, static_cast<int>(std::lround(scene.height * scale)));
    const double fx = static_cast<double>(width) / scene.width;
    const double fy = static_cast<double>(height) / scene.height;
    auto map = [fx, fy](Point& p) {
      p.x = (p.x + 0.5) * fx - 0.5;
      p.y = (p.y + 0.5) * fy - 0.5;
    };
    for (TrueInstance& t : scene.instances) {
      std::for_each(t.points.begin(), t.points.end(), map);
      std::for_each(t.polygon.begin(), t.polygon.end(), map);
      if (t.scale)
        *t.scale *= std::sqrt(fx * fy);
    }
    if (frames) {
      Frame& f = (*frames)[i];
      const int type = f.bgr ? CV_8UC3 : CV_8UC1;
      const cv::Mat original(f.height, f.width, type, f.pixels.data());
      cv::Mat resized;
      cv::resize(original, resized, cv::Size(width, height), 0, 0, cv::INTER_AREA);
      f.width = width;
      f.height = height;
      f.pixels.assign(resized.datastart, resized.dataend);
    }
    scene.width = width;
    scene.height = height;
  }
}

/// Changes the light of every frame: grey (or colour) levels v become
/// (128 + (v - 128) * contrast) * gain, rounded and clipped to 0..255. Gain under 1 is a frame
/// taken with less light, contrast under 1 a flatter (hazier) one; the truth stays as it is.
void relight_frames(std::vector<Frame>& frames, double gain, double contrast) {
  for (Frame& f : frames) {
    cv::Mat levels(1, static_cast<int>(f.pixels.size()), CV_8UC1, f.pixels.data());
    levels.convertTo(levels, CV_8UC1, contrast * gain, 128.0 * (1.0 - contrast) * gain);
  }
}

int run(int argc, char** argv) {
  Options o;
  const GOptionEntry entries[] = {
      {"method", 'm', 0, G_OPTION_ARG_STRING, &o.method,
       "Only this method: voting, ransac-clustered or ransac-all (default: all three)", "NAME"},
      {"detections-out", 'o', 0, G_OPTION_ARG_FILENAME, &o.detections_out,
       "Write the detections as JSON Lines (one line per scene and method)", "FILE"},
      {"json", 'j', 0, G_OPTION_ARG_NONE, &o.json,
       "Print the summary as JSON (per method: overall and per model)", nullptr},
      {"bgr", 0, 0, G_OPTION_ARG_NONE, &o.bgr, "Push BGR frames instead of GRAY8", nullptr},
      {"frame-scale", 0, 0, G_OPTION_ARG_DOUBLE, &o.frame_scale,
       "Resize every frame by F (area interpolation) before pushing it, and the ground truth "
       "with it (0 < F <= 1; 0.5 makes 1280x960 scenes 640x480)",
       "F"},
      {"frame-gain", 0, 0, G_OPTION_ARG_DOUBLE, &o.frame_gain,
       "Multiply every frame's levels by G before pushing it, clipped (0 < G <= 4; 0.3 is a "
       "frame taken with 30 % of the light)",
       "G"},
      {"frame-contrast", 0, 0, G_OPTION_ARG_DOUBLE, &o.frame_contrast,
       "Pull every frame's levels towards mid-grey to C of their contrast, before any gain "
       "(0 < C <= 1)",
       "C"},
      {"per-model", 0, 0, G_OPTION_ARG_NONE, &o.per_model,
       "One element per model, each with that model alone (default: one element with all the "
       "models)",
       nullptr},
      {"models", 0, 0, G_OPTION_ARG_STRING, &o.models,
       "Load and score only these of the dataset's models (comma-separated names; default: all)",
       "NAME,..."},
      {"score", 0, 0, G_OPTION_ARG_FILENAME, &o.score,
       "Score this detections file (JSON Lines) instead of running the element", "FILE"},
      {"ratio", 0, 0, G_OPTION_ARG_STRING, &o.ratio, "Element property ratio", "R"},
      {"bandwidth", 0, 0, G_OPTION_ARG_STRING, &o.bandwidth, "Element property bandwidth", "PX"},
      {"min-matches", 0, 0, G_OPTION_ARG_STRING, &o.min_matches, "Element property min-matches",
       "N"},
      {"allow-scale", 0, 0, G_OPTION_ARG_STRING, &o.allow_scale,
       "Element property allow-scale (true or false)", "BOOL"},
      {"max-instances", 0, 0, G_OPTION_ARG_STRING, &o.max_instances,
       "Element property max-instances", "N"},
      {"set", 's', 0, G_OPTION_ARG_STRING_ARRAY, &o.set, "Set any element property (repeatable)",
       "PROP=VALUE"},
      {G_OPTION_REMAINING, 0, 0, G_OPTION_ARG_FILENAME_ARRAY, &o.rest, nullptr, "DATASET_DIR"},
      {nullptr, 0, 0, G_OPTION_ARG_NONE, nullptr, nullptr, nullptr}};

  pickdetect::tools::OptionHelp help;
  help.summary =
      "Runs every scene of an annotated dataset (see the benchmark's FORMAT.md) through the "
      "pickdetect element\nonce per method, with all the dataset's models loaded at once (every "
      "detection counts: one\nof a model that is not in the scene is a false detection), and "
      "prints object, pixel, centre\nand pick figures per model and overall.";
  std::string bad_options;
  if (!pickdetect::tools::parse_options(argc, argv, entries, help, bad_options,
                                        gst_init_get_option_group())) {
    std::cerr << "pickdetect-eval: " << bad_options << "\n";
    return 2;
  }
  if (!o.rest || !o.rest[0] || o.rest[1]) {
    std::cerr << "pickdetect-eval: give exactly one DATASET_DIR (see --help)\n";
    return 2;
  }

  if (!(o.frame_scale > 0.0 && o.frame_scale <= 1.0)) {
    std::cerr << "pickdetect-eval: --frame-scale wants 0 < F <= 1, got " << o.frame_scale << "\n";
    return 2;
  }

  if (!(o.frame_gain > 0.0 && o.frame_gain <= 4.0)) {
    std::cerr << "pickdetect-eval: --frame-gain wants 0 < G <= 4, got " << o.frame_gain << "\n";
    return 2;
  }
  if (!(o.frame_contrast > 0.0 && o.frame_contrast <= 1.0)) {
    std::cerr << "pickdetect-eval: --frame-contrast wants 0 < C <= 1, got " << o.frame_contrast
              << "\n";
    return 2;
  }

  std::vector<std::string> methods;
  if (o.method) {
    bool known = false;
    for (const char* m : kMethods)
      known = known || g_strcmp0(m, o.method) == 0;
    if (!known) {
      std::cerr << "pickdetect-eval: unknown method '" << o.method
                << "' (voting, ransac-clustered or ransac-all)\n";
      return 2;
    }
    methods.push_back(o.method);
  } else {
    methods.assign(std::begin(kMethods), std::end(kMethods));
  }

  std::vector<std::pair<std::string, std::string>> properties;
  const std::pair<const char*, gchar*> named[] = {{"ratio", o.ratio},
                                                  {"bandwidth", o.bandwidth},
                                                  {"min-matches", o.min_matches},
                                                  {"allow-scale", o.allow_scale},
                                                  {"max-instances", o.max_instances}};
  for (const auto& [name, value] : named)
    if (value)
      properties.emplace_back(name, value);
  for (gchar** s = o.set; s && *s; ++s) {
    const char* eq = std::strchr(*s, '=');
    if (!eq || eq == *s) {
      std::cerr << "pickdetect-eval: --set wants PROP=VALUE, got '" << *s << "'\n";
      return 2;
    }
    const std::string name(*s, static_cast<size_t>(eq - *s)), value(eq + 1);
    if (name == "model" || name == "method") {
      std::cerr << "pickdetect-eval: --set " << name
                << " is chosen by the tool (use --method to restrict methods)\n";
      return 2;
    }
    if (name == "threads" && value != "1") {
      std::cerr << "pickdetect-eval: --set threads: the tool pushes one frame and waits for it, "
                   "and frame threads hold frames back; the instances do not depend on threads\n";
      return 2;
    }
    properties.emplace_back(name, value);
  }

  Dataset dataset = load_dataset(o.rest[0]);
  std::map<std::string, Scorer> scorers;

  // The models to load and score, in the dataset's order.
  std::vector<const ModelInfo*> models;
  if (o.models) {
    gchar** names = g_strsplit(o.models, ",", -1);
    for (gchar** n = names; *n; ++n) {
      const std::string name(g_strstrip(*n));
      const ModelInfo* m = dataset.find_model(name);
      if (!m) {
        std::cerr << "pickdetect-eval: --models: '" << name << "' is not one of the dataset's "
                  << "models\n";
        g_strfreev(names);
        return 2;
      }
      if (std::find(models.begin(), models.end(), m) == models.end())
        models.push_back(m);
    }
    g_strfreev(names);
    if (o.score) {
      std::cerr << "pickdetect-eval: --models applies to running the element, not to --score\n";
      return 2;
    }
    std::sort(models.begin(), models.end()); // Pointers into dataset.models: its order.
  } else {
    for (const ModelInfo& m : dataset.models)
      models.push_back(&m);
  }

  if (o.score) {
    const std::vector<SceneDetections> lines = load_detections(o.score);
    if (o.frame_scale != 1.0)
      scale_frames(dataset, nullptr, o.frame_scale);
    scorers = score_detections(dataset, lines);
  } else {
    std::vector<Frame> frames = load_frames(dataset, o.bgr);
    if (o.frame_scale != 1.0)
      scale_frames(dataset, &frames, o.frame_scale);
    if (o.frame_gain != 1.0 || o.frame_contrast != 1.0)
      relight_frames(frames, o.frame_gain, o.frame_contrast);
    GError* error = nullptr;
    gchar* tmp = g_dir_make_tmp("pickdetect-eval-XXXXXX", &error);
    if (!tmp) {
      std::cerr << "pickdetect-eval: " << error->message << "\n";
      g_clear_error(&error);
      return 1;
    }
    const std::string folder(tmp);
    g_free(tmp);
    std::map<std::string, std::string> model_files;
    std::vector<std::string> written;
    for (size_t k = 0; k < models.size(); ++k) {
      model_files[models[k]->name] = write_model_file(dataset, *models[k], folder);
      written.push_back(model_files[models[k]->name]);
    }
    auto cleanup = [&] {
      for (const std::string& f : written)
        g_remove(f.c_str());
      g_rmdir(folder.c_str());
    };

    // Each run is one element: all the models at once, or (--per-model) one model alone.
    std::vector<std::vector<const ModelInfo*>> runs;
    if (o.per_model) {
      for (const ModelInfo* m : models)
        runs.push_back({m});
    } else {
      runs.push_back(models);
    }

    // method -> scene -> detections of every model.
    std::map<std::string, std::vector<SceneDetections>> lines;
    Progress progress(methods.size() * runs.size() * frames.size());
    try {
      for (const std::string& method : methods) {
        Scorer& scorer = scorers.try_emplace(method, dataset).first->second;
        std::vector<SceneDetections>& out = lines[method];
        out.resize(frames.size());
        for (size_t i = 0; i < frames.size(); ++i) {
          out[i].image = frames[i].image;
          out[i].method = methods.size() > 1 ? method : std::string();
        }
        for (const std::vector<const ModelInfo*>& run : runs) {
          std::string model_list, label;
          for (const ModelInfo* m : run) {
            const std::string& file = model_files[m->name];
            if (file.find(',') != std::string::npos)
              throw RunError("the model file '" + file +
                             "' has a comma in its path, which the element's model list cannot "
                             "take (set TMPDIR to a folder without one)");
            model_list += (model_list.empty() ? "" : ",") + file;
            label += (label.empty() ? "" : "+") + m->name;
          }
          std::vector<std::pair<std::string, std::string>> props = {{"model", model_list},
                                                                    {"method", method}};
          props.insert(props.end(), properties.begin(), properties.end());
          ElementRunner runner(props);
          if (dataset.fps) // A video sequence: one stream, timestamps at its frame rate.
            runner.set_fps(*dataset.fps);
          for (size_t i = 0; i < frames.size(); ++i) {
            FrameResult r = runner.process(frames[i]);
            for (const DetectedInstance& d : r.instances) {
              if (std::none_of(run.begin(), run.end(),
                               [&](const ModelInfo* m) { return m->name == d.model; }))
                throw RunError("scene '" + frames[i].image +
                               "': the element named an instance's model '" + d.model +
                               "', which is not among the models loaded (" + label + ")");
              if (d.polygon.size() < 3 || d.points.empty())
                throw RunError("scene '" + frames[i].image +
                               "': an instance in the metadata has no outline or no centre");
            }
            // Every detection counts against every loaded model: one of a model that is not in
            // the scene is a false detection.
            for (const ModelInfo* m : run)
              scorer.add_scene(i, r.instances, m->name);
            if (o.per_model) {
              scorer.add_time(i, run[0]->name, r.ms);
              out[i].ms[run[0]->name] = r.ms;
            } else {
              scorer.add_frame_time(i, r.ms);
              out[i].frame_ms = r.ms;
            }
            out[i].instances.insert(out[i].instances.end(), r.instances.begin(), r.instances.end());
            progress.step(method + " / " + label);
          }
        }
      }
    } catch (...) {
      progress.abort();
      cleanup();
      throw;
    }
    cleanup();
    if (o.detections_out) {
      std::ofstream file(o.detections_out);
      for (const std::string& method : methods)
        for (const SceneDetections& s : lines[method])
          file << detections_line(s) << "\n";
      file.close();
      if (!file) {
        std::cerr << "pickdetect-eval: cannot write '" << o.detections_out << "'\n";
        return 1;
      }
    }
  }

  if (o.json)
    std::cout << report_json(dataset, scorers) << "\n";
  else
    std::cout << "dataset " << dataset.name << ": " << dataset.scenes.size() << " scenes\n\n"
              << report_table(dataset, scorers);
  return 0;
}

} // namespace

int main(int argc, char** argv) {
#if defined(PICKDETECT_EVAL_BUILD_DIR) && defined(PICKDETECT_PLUGIN_BUILD_DIR)
  pickdetect::tools::use_build_tree_plugin(PICKDETECT_PLUGIN_BUILD_DIR, PICKDETECT_EVAL_BUILD_DIR);
#endif
  try {
    return run(argc, argv);
  } catch (const FormatError& e) {
    std::cerr << "pickdetect-eval: " << e.what() << "\n";
    return 1;
  } catch (const RunError& e) {
    std::cerr << "pickdetect-eval: " << e.what() << "\n";
    return 1;
  }
}
