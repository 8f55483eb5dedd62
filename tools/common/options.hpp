// SPDX-License-Identifier: LGPL-2.1-or-later
// The command line of the pickdetect-* tools: one GOption parse, with their help texts.
#pragma once

#include <glib.h>

#include <string>

namespace pickdetect::tools {

/// The help texts of a tool's --help.
struct OptionHelp {
  const char* parameter = nullptr;   ///< After the tool's name on the usage line ("PICTURE...").
  const char* summary = nullptr;     ///< Before the options.
  const char* description = nullptr; ///< After the options.
};

/// Parses the command line with `entries` (and `group` as well unless null, e.g. GStreamer's
/// gst_init_get_option_group(); taken). False, with `error` set to GLib's message, when the
/// command line is wrong.
bool parse_options(int& argc, char**& argv, const GOptionEntry* entries, const OptionHelp& help,
                   std::string& error, GOptionGroup* group = nullptr);

} // namespace pickdetect::tools
