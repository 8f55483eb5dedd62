// SPDX-License-Identifier: LGPL-2.1-or-later
// Errors: why reading a file failed.
#include <pickdetect/error.hpp>

#include <filesystem>
#include <system_error>
#include <unistd.h>

namespace pickdetect {

ErrorKind file_error_kind(const std::string& path) {
  if (::access(path.c_str(), F_OK) != 0)
    return ErrorKind::NotFound;
  std::error_code ec;
  if (::access(path.c_str(), R_OK) != 0 || std::filesystem::is_directory(path, ec))
    return ErrorKind::CannotRead;
  return ErrorKind::Invalid;
}

} // namespace pickdetect
