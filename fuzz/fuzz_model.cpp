// SPDX-License-Identifier: LGPL-2.1-or-later
// libFuzzer target: the model loader. First byte even: the rest is a model file (YAML text,
// beside small.png and box.png it may name, also several views); odd: the rest is a picture file
// given as the model. Any refusal must be a pickdetect::Error; a loaded model must be usable.
#include "fuzz_common.hpp"

#include <pickdetect/detector.hpp>
#include <pickdetect/error.hpp>
#include <pickdetect/model.hpp>

#include <cstdio>
#include <fstream>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  fuzz::Input in(data, size);
  const bool picture = in.byte() & 1;
  const std::string path = fuzz::work_dir() + (picture ? "/input.png" : "/input.yml");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(in.rest()),
              static_cast<std::streamsize>(in.rest_size()));
  }
  try {
    // A model file may list several views of one product, each a model.
    const std::vector<pickdetect::Model> views = pickdetect::load_views(path);
    if (views.empty())
      __builtin_trap();
    // A model that loads holds together: points, outline, features that agree.
    for (const pickdetect::Model& model : views)
      if (model.principal_points.empty() || model.outline.size() < 3 ||
          model.sift.keypoints.size() < static_cast<size_t>(pickdetect::kMinModelKeypoints) ||
          model.grasp_point < 0 ||
          model.grasp_point >= static_cast<int>(model.principal_points.size()) ||
          (!model.colour.empty() && model.colour.size() != model.image.size()))
        __builtin_trap();
    pickdetect::Detector detector(views);
    detector.detect(views.front().image, views.front().colour);
  } catch (const pickdetect::Error&) {
  }
  std::remove(path.c_str());
  return 0;
}
