// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <pickdetect/export.hpp>

#include <stdexcept>
#include <string>
#include <utility>

namespace pickdetect {

/// What kind of refusal an Error is, for callers that report them by class (the element maps
/// them to GStreamer's resource errors).
enum class ErrorKind {
  Invalid,    ///< Wrong contents or settings: a bad model file, a textureless picture, a bad list.
  NotFound,   ///< The file named does not exist.
  CannotRead, ///< The file exists but cannot be read (no permission, a directory).
};

/// Every refusal of the core (bad model file, textureless picture, bad frame) is an Error whose
/// message names what was wrong and, where there is one, the file. Errors about a file carry
/// its path and the kind of failure (file_error_kind of that path).
class PICKDETECT_API Error : public std::runtime_error {
public:
  explicit Error(const std::string& what, ErrorKind kind = ErrorKind::Invalid,
                 std::string path = {})
      : std::runtime_error(what), kind_(kind), path_(std::move(path)) {}

  ErrorKind kind() const { return kind_; }
  /// The file that was being read when it failed; empty when the error is not about one file.
  const std::string& path() const { return path_; }

private:
  ErrorKind kind_;
  std::string path_;
};

/// Why reading `path` failed: NotFound when it does not exist, CannotRead when it cannot be
/// opened for reading (or is a directory), else Invalid (its contents were wrong).
PICKDETECT_API ErrorKind file_error_kind(const std::string& path);

} // namespace pickdetect
