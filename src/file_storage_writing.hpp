// SPDX-License-Identifier: LGPL-2.1-or-later
// Internal to the core: opening an OpenCV FileStorage for writing, with the same Error for a
// model file and a calibration file that cannot be written.
#pragma once

#include <pickdetect/error.hpp>

#include <opencv2/core/persistence.hpp>

#include <string>

namespace pickdetect::detail {

/// Opens `store` to write `path`; throws an Error "<what> '<path>' cannot be written" (with
/// OpenCV's reason when it gave one) when it cannot. `what` names the file's kind, e.g.
/// "model file".
inline void open_for_writing(cv::FileStorage& store, const std::string& path,
                             const std::string& what) {
  const std::string file = what + " '" + path + "'";
  try {
    store.open(path, cv::FileStorage::WRITE);
  } catch (const cv::Exception& e) {
    throw Error(file + " cannot be written: " + e.err);
  }
  if (!store.isOpened())
    throw Error(file + " cannot be written");
}

} // namespace pickdetect::detail
