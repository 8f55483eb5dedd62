// SPDX-License-Identifier: LGPL-2.1-or-later
// Model lists: comma-separated model files, pictures and model-set files, loaded as one list of
// models with distinct names, one per view of each product (what the element's `model`
// property and the tools take).
#include <pickdetect/error.hpp>
#include <pickdetect/model.hpp>

#include <opencv2/core/persistence.hpp>

#include <exception>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace fs = std::filesystem;

namespace pickdetect {
namespace {

/// The entries of a model list: split at commas, blanks around each entry trimmed. An empty list
/// has no entries.
std::vector<std::string> split_model_list(const std::string& list) {
  std::vector<std::string> entries;
  if (list.empty())
    return entries;
  const char* const blanks = " \t\n\v\f\r";
  size_t start = 0;
  for (;;) {
    const size_t comma = list.find(',', start);
    const std::string part =
        list.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const size_t first = part.find_first_not_of(blanks);
    entries.push_back(first == std::string::npos
                          ? std::string()
                          : part.substr(first, part.find_last_not_of(blanks) - first + 1));
    if (comma == std::string::npos)
      break;
    start = comma + 1;
  }
  return entries;
}

/// Reads a model-set file (a model file with a `models` list and no `image`) into the paths of
/// its models, made relative to the set file's folder. Returns false when `path` is not a model
/// set (it is then a model file or picture, or broken, which load_model reports). Throws Error
/// when it is a model set that is malformed.
bool read_model_set(const std::string& path, std::vector<std::string>& models) {
  std::error_code ec;
  if (!is_model_file(path) || !fs::is_regular_file(path, ec))
    return false;
  cv::FileStorage store;
  try {
    if (!store.open(path, cv::FileStorage::READ))
      return false;
  } catch (const cv::Exception&) {
    return false;
  }
  const cv::FileNode root = store.root();
  if (!root.isMap() || root["models"].empty() || !root["image"].empty())
    return false;
  const std::string origin = "model set \"" + path + "\"";
  const cv::FileNode list = root["models"];
  if (!list.isSeq() || list.size() == 0)
    throw Error(origin + ": 'models' must be a non-empty list of model files");
  fs::path folder = fs::path(path).parent_path();
  if (folder.empty())
    folder = ".";
  for (size_t i = 0; i < list.size(); i++) {
    const cv::FileNode item = list[static_cast<int>(i)];
    const std::string entry = item.isString() ? static_cast<std::string>(item) : std::string();
    if (entry.empty())
      throw Error(origin + ": models[" + std::to_string(i) +
                  "] must be the path of a model file or picture");
    models.push_back(fs::path(entry).is_absolute() ? entry : (folder / entry).string());
  }
  return true;
}

/// Loads the models of one entry of a model list (a model file, a picture or a model set) onto
/// `models`, and the file each came from onto `sources`. Throws Error naming the file being read
/// and why it failed.
void load_entry(const std::string& entry, std::vector<Model>& models,
                std::vector<std::string>& sources) {
  std::string path = entry; // The file being read when something failed.
  try {
    std::vector<std::string> listed;
    if (!read_model_set(entry, listed))
      listed.push_back(entry);
    for (const std::string& file : listed) {
      path = file;
      std::vector<std::string> nested;
      if (file != entry && read_model_set(file, nested))
        throw Error("model set \"" + entry + "\" lists another model set, \"" + file +
                    "\"; list that set's models instead");
      for (Model& view : load_views(file)) {
        models.push_back(std::move(view));
        sources.push_back(file);
      }
    }
  } catch (const std::exception& e) {
    throw Error(e.what(), file_error_kind(path), path);
  } catch (...) {
    throw Error("unknown error", file_error_kind(path), path);
  }
}

} // namespace

std::vector<Model> load_models(const std::string& list) {
  std::vector<Model> models;
  std::vector<std::string> sources; // The file each model came from.
  for (const std::string& entry : split_model_list(list)) {
    if (entry.empty())
      throw Error("the comma-separated list has an empty entry");
    load_entry(entry, models, sources);
  }
  // Instances are told apart by their model's name only; the same model twice would also make
  // every one of its features ambiguous, so that none would match. The views of one product
  // (one model file) share its name, and their names differ (load_views).
  for (size_t i = 0; i < models.size(); i++)
    for (size_t j = 0; j < i; j++)
      if (models[i].name == models[j].name &&
          (sources[i] != sources[j] || models[i].view == models[j].view))
        throw Error("two models are named \"" + models[i].name + "\" (" + sources[j] + " and " +
                    sources[i] + "); give each model a distinct name (the `name` key of a model " +
                    "file)");
  return models;
}

} // namespace pickdetect
