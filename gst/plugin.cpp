// SPDX-License-Identifier: LGPL-2.1-or-later
// The pickdetect plugin: the pickdetect element and pickdetectjson, its JSON lines.
#include "gstpickdetect.h"
#include "gstpickdetectjson.h"

static gboolean plugin_init(GstPlugin* plugin) {
  gboolean ok = GST_ELEMENT_REGISTER(pickdetect, plugin);
  ok &= GST_ELEMENT_REGISTER(pickdetectjson, plugin);
  return ok;
}

// The origin is the project's name: it has no public home page to point to.
GST_PLUGIN_DEFINE(GST_VERSION_MAJOR, GST_VERSION_MINOR, pickdetect,
                  "Detection of multiple object instances for pick-and-place", plugin_init,
                  PICKDETECT_VERSION, "LGPL", PACKAGE, PACKAGE)
