// SPDX-License-Identifier: LGPL-2.1-or-later
// The build tree's pickdetect plugin, for programs run from the build tree.
#pragma once

namespace pickdetect::tools {

/// Puts `plugin_dir` (the build tree's gst/ folder) first on GST_PLUGIN_PATH, before gst_init,
/// when it exists; with `only_from_dir`, only when the running binary lies in that folder (an
/// installed binary then relies on GStreamer's usual plugin search).
void use_build_tree_plugin(const char* plugin_dir, const char* only_from_dir = nullptr);

} // namespace pickdetect::tools
