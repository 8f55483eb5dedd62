// SPDX-License-Identifier: LGPL-2.1-or-later
// pickdetect-eval: measures the pickdetect element's accuracy on an annotated dataset.
//
//   pickdetect-eval DATASET_DIR
//   pickdetect-eval --method voting --json --detections-out voting.jsonl DATASET_DIR
//   pickdetect-eval --score detections.jsonl DATASET_DIR     (scores a file, runs nothing)
//
// Every scene goes through the real element (appsrc ! pickdetect ! appsink), once per method
// and per model, and the instances are read back from the buffers' metadata. The plugin is
// found through GST_PLUGIN_PATH; a binary run from its build tree also looks in the build
// tree's gst/ folder first.
#include "dataset.hpp"
#include "metrics.hpp"
#include "runner.hpp"

#include <glib/gstdio.h>
#include <gst/gst.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <unistd.h>

using namespace pickdetect::eval;

namespace {

const char* const kMethods[] = {"voting", "ransac-clustered", "ransac-all"};

/// Lets a binary in the build tree use the plugin built beside it.
void use_build_tree_plugin() {
#if defined(PICKDETECT_EVAL_BUILD_DIR) && defined(PICKDETECT_PLUGIN_BUILD_DIR)
  gchar* exe = g_file_read_link("/proc/self/exe", nullptr);
  if (!exe)
    return;
  gchar* dir = g_path_get_dirname(exe);
  gchar* here = g_canonicalize_filename(dir, nullptr);
  gchar* build = g_canonicalize_filename(PICKDETECT_EVAL_BUILD_DIR, nullptr);
  if (g_strcmp0(here, build) == 0 && g_file_test(PICKDETECT_PLUGIN_BUILD_DIR, G_FILE_TEST_IS_DIR)) {
    const gchar* old = g_getenv("GST_PLUGIN_PATH");
    gchar* path = old && *old ? g_strconcat(PICKDETECT_PLUGIN_BUILD_DIR, G_SEARCHPATH_SEPARATOR_S,
                                            old, nullptr)
                              : g_strdup(PICKDETECT_PLUGIN_BUILD_DIR);
    g_setenv("GST_PLUGIN_PATH", path, TRUE);
    g_free(path);
  }
  g_free(build);
  g_free(here);
  g_free(dir);
  g_free(exe);
#endif
}

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
    g_free(ratio);
    g_free(bandwidth);
    g_free(min_matches);
    g_free(allow_scale);
    g_free(max_instances);
    g_strfreev(set);
    g_strfreev(rest);
  }
};

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

  GOptionContext* context = g_option_context_new(nullptr);
  g_option_context_set_summary(
      context, "Runs every scene of an annotated dataset (see the benchmark's FORMAT.md) through "
               "the pickdetect element\nonce per method and model, and prints object, pixel, "
               "centre and pick figures per model and overall.");
  g_option_context_add_main_entries(context, entries, nullptr);
  g_option_context_add_group(context, gst_init_get_option_group());
  GError* error = nullptr;
  const gboolean parsed = g_option_context_parse(context, &argc, &argv, &error);
  g_option_context_free(context);
  if (!parsed) {
    std::cerr << "pickdetect-eval: " << error->message << "\n";
    g_clear_error(&error);
    return 2;
  }
  if (!o.rest || !o.rest[0] || o.rest[1]) {
    std::cerr << "pickdetect-eval: give exactly one DATASET_DIR (see --help)\n";
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
    properties.emplace_back(name, value);
  }

  const Dataset dataset = load_dataset(o.rest[0]);
  std::map<std::string, Scorer> scorers;

  if (o.score) {
    const std::vector<SceneDetections> lines = load_detections(o.score);
    scorers = score_detections(dataset, lines);
  } else {
    const std::vector<Frame> frames = load_frames(dataset, o.bgr);
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
    for (const ModelInfo& m : dataset.models) {
      model_files[m.name] = write_model_file(dataset, m, folder);
      written.push_back(model_files[m.name]);
    }
    auto cleanup = [&] {
      for (const std::string& f : written)
        g_remove(f.c_str());
      g_rmdir(folder.c_str());
    };

    // method -> scene -> detections of every model.
    std::map<std::string, std::vector<SceneDetections>> lines;
    Progress progress(methods.size() * dataset.models.size() * frames.size());
    try {
      for (const std::string& method : methods) {
        Scorer& scorer = scorers.try_emplace(method, dataset).first->second;
        std::vector<SceneDetections>& out = lines[method];
        out.resize(frames.size());
        for (size_t i = 0; i < frames.size(); ++i) {
          out[i].image = frames[i].image;
          out[i].method = methods.size() > 1 ? method : std::string();
        }
        for (const ModelInfo& m : dataset.models) {
          std::vector<std::pair<std::string, std::string>> props = {{"model", model_files[m.name]},
                                                                    {"method", method}};
          props.insert(props.end(), properties.begin(), properties.end());
          ElementRunner runner(props);
          for (size_t i = 0; i < frames.size(); ++i) {
            FrameResult r = runner.process(frames[i]);
            std::vector<DetectedInstance> mine;
            for (DetectedInstance& d : r.instances) {
              if (d.model != m.name)
                throw RunError("scene '" + frames[i].image +
                               "': the element named an instance's model '" + d.model +
                               "', expected '" + m.name + "'");
              if (d.polygon.size() < 3 || d.points.empty())
                throw RunError("scene '" + frames[i].image +
                               "': an instance in the metadata has no outline or no centre");
              mine.push_back(std::move(d));
            }
            scorer.add_scene(i, mine, m.name);
            scorer.add_time(i, m.name, r.ms);
            out[i].ms[m.name] = r.ms;
            out[i].instances.insert(out[i].instances.end(), mine.begin(), mine.end());
            progress.step(method + " / " + m.name);
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
  use_build_tree_plugin();
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
