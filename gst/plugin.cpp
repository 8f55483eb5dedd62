// SPDX-License-Identifier: LGPL-2.1-or-later
// The pickdetect plugin: the pickdetect element.
#include "gstpickdetect.h"

static gboolean plugin_init(GstPlugin* plugin) {
  return GST_ELEMENT_REGISTER(pickdetect, plugin);
}

GST_PLUGIN_DEFINE(GST_VERSION_MAJOR, GST_VERSION_MINOR, pickdetect,
                  "Detection of multiple object instances for pick-and-place", plugin_init,
                  PICKDETECT_VERSION, "LGPL", PACKAGE, "https://example.invalid/gst-pickdetect")
