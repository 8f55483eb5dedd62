/* SPDX-License-Identifier: LGPL-2.1-or-later */
#pragma once

#include <gst/gst.h>

G_BEGIN_DECLS

#define GST_TYPE_PICK_DETECT_JSON (gst_pick_detect_json_get_type())
G_DECLARE_FINAL_TYPE(GstPickDetectJson, gst_pick_detect_json, GST, PICK_DETECT_JSON, GstElement)

GST_ELEMENT_REGISTER_DECLARE(pickdetectjson);

G_END_DECLS
