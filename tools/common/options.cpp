// SPDX-License-Identifier: LGPL-2.1-or-later
#include "options.hpp"

#include <memory>

namespace pickdetect::tools {

bool parse_options(int& argc, char**& argv, const GOptionEntry* entries, const OptionHelp& help,
                   std::string& error, GOptionGroup* group) {
  std::unique_ptr<GOptionContext, decltype(&g_option_context_free)> context(
      g_option_context_new(help.parameter), g_option_context_free);
  if (help.summary)
    g_option_context_set_summary(context.get(), help.summary);
  if (help.description)
    g_option_context_set_description(context.get(), help.description);
  g_option_context_add_main_entries(context.get(), entries, nullptr);
  if (group)
    g_option_context_add_group(context.get(), group);
  GError* err = nullptr;
  if (g_option_context_parse(context.get(), &argc, &argv, &err))
    return true;
  error = err->message;
  g_error_free(err);
  return false;
}

} // namespace pickdetect::tools
