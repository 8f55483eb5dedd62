// SPDX-License-Identifier: LGPL-2.1-or-later
#include "plugin-path.hpp"

#include <glib.h>

namespace pickdetect::tools {
namespace {

/// Whether the running binary lies in `dir`.
bool runs_from(const char* dir) {
  gchar* exe = g_file_read_link("/proc/self/exe", nullptr);
  if (!exe)
    return false;
  gchar* exe_dir = g_path_get_dirname(exe);
  gchar* here = g_canonicalize_filename(exe_dir, nullptr);
  gchar* there = g_canonicalize_filename(dir, nullptr);
  const bool same = g_strcmp0(here, there) == 0;
  g_free(there);
  g_free(here);
  g_free(exe_dir);
  g_free(exe);
  return same;
}

} // namespace

void use_build_tree_plugin(const char* plugin_dir, const char* only_from_dir) {
  if (only_from_dir && !runs_from(only_from_dir))
    return;
  if (!g_file_test(plugin_dir, G_FILE_TEST_IS_DIR))
    return;
  const gchar* old = g_getenv("GST_PLUGIN_PATH");
  gchar* path = old && *old ? g_strconcat(plugin_dir, G_SEARCHPATH_SEPARATOR_S, old, nullptr)
                            : g_strdup(plugin_dir);
  g_setenv("GST_PLUGIN_PATH", path, TRUE);
  g_free(path);
}

} // namespace pickdetect::tools
