// SPDX-License-Identifier: LGPL-2.1-or-later
#pragma once

#include <stdexcept>
#include <string>

namespace pickdetect {

/// Every refusal of the core (bad model file, textureless picture, bad frame) is an Error whose
/// message names what was wrong and, where there is one, the file.
class Error : public std::runtime_error {
public:
  explicit Error(const std::string& what) : std::runtime_error(what) {}
};

} // namespace pickdetect
