// SPDX-License-Identifier: LGPL-2.1-or-later
// pickdetect-detect: runs the detection core on still pictures and prints every instance.
//
//   pickdetect-detect --model box.png box_in_scene.png
//   pickdetect-detect --model cookies.yml --method ransac-clustered --annotate out.png scene.jpg
#include "common/options.hpp"

#include <pickdetect/pickdetect.hpp>

#include <glib.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

namespace {

void draw(cv::Mat& bgr, const std::vector<pickdetect::Instance>& instances) {
  const cv::Scalar white(255, 255, 255), green(0, 255, 0);
  const cv::Scalar point_colours[] = {{255, 0, 0}, {255, 0, 255}, {0, 255, 255}, {0, 255, 0}};
  for (const pickdetect::Instance& inst : instances) {
    std::vector<cv::Point> outline;
    for (const cv::Point2f& p : inst.outline)
      outline.emplace_back(cvRound(p.x), cvRound(p.y));
    cv::polylines(bgr, outline, true, white, 2, cv::LINE_AA);
    for (size_t j = 1; j < inst.points.size(); ++j)
      cv::circle(bgr, inst.points[j], 5, point_colours[(j - 1) % 4], 2, cv::LINE_AA);
    cv::circle(bgr, inst.center, 12, green, 3, cv::LINE_AA);
    cv::putText(bgr, std::to_string(inst.matches), inst.center + cv::Point2f(14.f, -14.f),
                cv::FONT_HERSHEY_SIMPLEX, 0.7, green, 2, cv::LINE_AA);
  }
}

void print_points(const std::vector<cv::Point2f>& points) {
  std::printf("[");
  for (size_t j = 0; j < points.size(); ++j)
    std::printf("%s[%.3f, %.3f]", j ? ", " : "", points[j].x, points[j].y);
  std::printf("]");
}

/// One line of the benchmark's detections format (JSON Lines).
void print_json(const char* picture, const std::vector<pickdetect::Instance>& instances) {
  gchar* name = g_strescape(picture, nullptr);
  std::printf("{\"image\": \"%s\", \"instances\": [", name);
  g_free(name);
  for (size_t i = 0; i < instances.size(); ++i) {
    const pickdetect::Instance& inst = instances[i];
    gchar* model = g_strescape(inst.model_name.c_str(), nullptr);
    std::printf("%s{\"model\": \"%s\", ", i ? ", " : "", model);
    g_free(model);
    if (!inst.view.empty()) {
      gchar* view = g_strescape(inst.view.c_str(), nullptr);
      std::printf("\"view\": \"%s\", ", view);
      g_free(view);
    }
    std::printf("\"points\": ");
    print_points(inst.points);
    std::printf(", \"polygon\": ");
    print_points(inst.outline);
    std::printf(", \"score\": %.4f, \"matches\": %d, \"pickable\": %s}", inst.score, inst.matches,
                inst.pickable ? "true" : "false");
  }
  std::printf("]}\n");
}

} // namespace

int main(int argc, char** argv) {
  gchar** models = nullptr;
  gchar* method = nullptr;
  gchar* features = nullptr;
  gchar* annotate = nullptr;
  gchar* save = nullptr;
  gdouble ratio = pickdetect::Settings().ratio;
  gdouble detection_scale = pickdetect::Settings().detection_scale;
  gdouble bandwidth = pickdetect::Settings().bandwidth;
  gint min_matches = pickdetect::Settings().min_matches;
  gint max_instances = pickdetect::Settings().max_instances;
  gboolean no_scale = FALSE, no_refine = FALSE, json = FALSE, exact = FALSE;
  const GOptionEntry entries[] = {
      {"model", 'm', 0, G_OPTION_ARG_FILENAME_ARRAY, &models,
       "Model file (.yml), model picture or model-set file, or several separated by commas (as "
       "the element's model property); repeat for more models",
       "FILE"},
      {"method", 0, 0, G_OPTION_ARG_STRING, &method,
       "voting (default), ransac-clustered or ransac-all", "NAME"},
      {"features", 0, 0, G_OPTION_ARG_STRING, &features,
       "sift (default, the paper's) or orb (fast)", "NAME"},
      {"detection-scale", 0, 0, G_OPTION_ARG_DOUBLE, &detection_scale,
       "Extract features from the picture shrunk by this factor (default 1)", "F"},
      {"ratio", 0, 0, G_OPTION_ARG_DOUBLE, &ratio,
       "2NN ratio test threshold (default 0: 0.9 for voting, 0.8 with --no-refine or a RANSAC "
       "method)",
       "R"},
      {"min-matches", 0, 0, G_OPTION_ARG_INT, &min_matches,
       "Fewest matches an instance needs (default 4)", "N"},
      {"bandwidth", 0, 0, G_OPTION_ARG_DOUBLE, &bandwidth,
       "Mean-shift bandwidth in pixels (default 0 = automatic)", "PX"},
      {"max-instances", 0, 0, G_OPTION_ARG_INT, &max_instances,
       "At most this many instances per picture (default 0 = no limit)", "N"},
      {"no-scale", 0, 0, G_OPTION_ARG_NONE, &no_scale,
       "Assume the objects are at the model's scale (the paper's assumption)", nullptr},
      {"no-refine", 0, 0, G_OPTION_ARG_NONE, &no_refine,
       "The paper's plain voting: the pose from the principal points' modes (no refit on "
       "inliers), features that fit several models alike rejected",
       nullptr},
      {"exact", 0, 0, G_OPTION_ARG_NONE, &exact,
       "Match by brute force (exact) instead of FLANN kd-trees", nullptr},
      {"json", 0, 0, G_OPTION_ARG_NONE, &json,
       "Print one JSON line per picture (the benchmark's detections format) instead of text",
       nullptr},
      {"annotate", 'o', 0, G_OPTION_ARG_FILENAME, &annotate,
       "Write the (last) picture with the instances drawn on it", "FILE"},
      {"save-model", 0, 0, G_OPTION_ARG_FILENAME, &save,
       "Write the (first) model, all its views, as a model file with its features cached", "FILE"},
      {nullptr, 0, 0, G_OPTION_ARG_NONE, nullptr, nullptr, nullptr}};

  pickdetect::tools::OptionHelp help;
  help.parameter = "PICTURE... - find every instance of a model in pictures";
  std::string bad_options;
  if (!pickdetect::tools::parse_options(argc, argv, entries, help, bad_options)) {
    std::fprintf(stderr, "pickdetect-detect: %s\n", bad_options.c_str());
    return 2;
  }
  auto cleanup = [&] {
    g_strfreev(models);
    g_free(method);
    g_free(features);
    g_free(annotate);
    g_free(save);
  };
  if (!models || !models[0] || (argc < 2 && !save)) {
    std::fprintf(stderr, "pickdetect-detect: give --model FILE and at least one picture\n");
    cleanup();
    return 2;
  }

  int status = 0;
  try {
    pickdetect::Settings s;
    if (method)
      s.method = pickdetect::parse_method(method);
    if (features)
      s.features = pickdetect::parse_features(features);
    s.ratio = ratio;
    s.detection_scale = detection_scale;
    s.bandwidth = bandwidth;
    s.min_matches = min_matches;
    s.max_instances = max_instances;
    s.allow_scale = !no_scale;
    s.refine = !no_refine;
    s.search = exact ? pickdetect::Search::BruteForce : pickdetect::Search::KdTree;

    std::vector<pickdetect::Model> loaded;
    for (gchar** m = models; *m; ++m) {
      std::vector<pickdetect::Model> listed = pickdetect::load_models(*m);
      std::move(listed.begin(), listed.end(), std::back_inserter(loaded));
    }
    if (save && loaded.front().view.empty()) {
      pickdetect::save_model(loaded.front(), save, true);
    } else if (save) { // Every view of the first product.
      std::vector<pickdetect::Model> views;
      std::copy_if(loaded.begin(), loaded.end(), std::back_inserter(views),
                   [&](const pickdetect::Model& m) { return m.name == loaded.front().name; });
      pickdetect::save_views(views, save, true);
    }
    const pickdetect::Detector detector(std::move(loaded));

    for (int a = 1; a < argc; ++a) {
      cv::Mat bgr = cv::imread(argv[a], cv::IMREAD_COLOR);
      if (bgr.empty())
        throw pickdetect::Error(std::string("picture '") + argv[a] + "' cannot be read");
      cv::Mat grey;
      cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
      // The colour tells look-alike products that differ in colour apart.
      const pickdetect::Detection d = detector.detect(grey, bgr, s);
      if (json) {
        print_json(argv[a], d.instances);
        continue;
      }
      std::printf("%s: %zu instance(s), %d keypoints, %d matches, %.0f ms (%s; features %.0f, "
                  "matching %.0f, voting and the rest %.0f)\n",
                  argv[a], d.instances.size(), d.scene_keypoints, d.matches,
                  d.timings.features_ms + d.timings.matching_ms + d.timings.clustering_ms,
                  pickdetect::method_name(s.method), d.timings.features_ms, d.timings.matching_ms,
                  d.timings.clustering_ms);
      for (const pickdetect::Instance& inst : d.instances) {
        std::printf("  %s%s%s centre=(%.1f, %.1f) angle=%.1f scale=%.3f matches=%d score=%.2f "
                    "pickable=%s points=",
                    inst.model_name.c_str(), inst.view.empty() ? "" : " view=", inst.view.c_str(),
                    inst.center.x, inst.center.y, inst.angle, inst.scale, inst.matches, inst.score,
                    inst.pickable ? "yes" : "no");
        for (size_t j = 0; j < inst.points.size(); ++j)
          std::printf("%s(%.1f, %.1f)", j ? " " : "", inst.points[j].x, inst.points[j].y);
        std::printf("\n");
      }
      if (annotate && a == argc - 1) {
        draw(bgr, d.instances);
        if (!cv::imwrite(annotate, bgr))
          throw pickdetect::Error(std::string("cannot write '") + annotate + "'");
        std::printf("annotated picture: %s\n", annotate);
      }
    }
  } catch (const pickdetect::Error& e) {
    std::fprintf(stderr, "pickdetect-detect: %s\n", e.what());
    status = 1;
  } catch (const cv::Exception& e) {
    std::fprintf(stderr, "pickdetect-detect: OpenCV: %s\n", e.what());
    status = 1;
  }
  cleanup();
  return status;
}
