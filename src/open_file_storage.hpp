// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: opening an OpenCV FileStorage to read or write a model file or a
// calibration file, with the same Errors for both.
#pragma once

#include <pickdetect/error.hpp>

#include <opencv2/core/persistence.hpp>

#include <string>

namespace pickdetect::detail {

/// Opens `store` to read `path`; throws an Error "<origin> cannot be parsed" or "<origin> is not
/// valid YAML/XML/JSON: <OpenCV's reason>" when it cannot. `origin` names the file in messages,
/// e.g. "model file 'parts.yml'".
inline void open_for_reading(cv::FileStorage& store, const std::string& path,
                             const std::string& origin) {
  try {
    if (!store.open(path, cv::FileStorage::READ))
      throw Error(origin + " cannot be parsed");
  } catch (const cv::Exception& e) {
    throw Error(origin + " is not valid YAML/XML/JSON: " + e.err);
  }
}

/// Opens `store` to write `path`; throws an Error "<origin> cannot be written" (with OpenCV's
/// reason when it gave one) when it cannot.
inline void open_for_writing(cv::FileStorage& store, const std::string& path,
                             const std::string& origin) {
  try {
    store.open(path, cv::FileStorage::WRITE);
  } catch (const cv::Exception& e) {
    throw Error(origin + " cannot be written: " + e.err);
  }
  if (!store.isOpened())
    throw Error(origin + " cannot be written");
}

} // namespace pickdetect::detail
