/* SPDX-License-Identifier: LGPL-2.1-or-later */
#pragma once

#include <gst/gst.h>
#include <gst/video/gstvideofilter.h>

G_BEGIN_DECLS

/**
 * GstPickDetectMethod:
 * @GST_PICK_DETECT_METHOD_VOTING: centre votes of every match, mean shift, principal points
 * @GST_PICK_DETECT_METHOD_RANSAC_CLUSTERED: one RANSAC homography per mean-shift cluster
 * @GST_PICK_DETECT_METHOD_RANSAC_ALL: one RANSAC homography over all matches (one instance)
 */
typedef enum {
  GST_PICK_DETECT_METHOD_VOTING,
  GST_PICK_DETECT_METHOD_RANSAC_CLUSTERED,
  GST_PICK_DETECT_METHOD_RANSAC_ALL,
} GstPickDetectMethod;

#define GST_TYPE_PICK_DETECT_METHOD (gst_pick_detect_method_get_type())
GType gst_pick_detect_method_get_type(void);

/**
 * GstPickDetectFeatures:
 * @GST_PICK_DETECT_FEATURES_SIFT: SIFT (the paper's): the most distinctive, the most costly
 * @GST_PICK_DETECT_FEATURES_ORB: ORB: oriented FAST corners, binary descriptors, much cheaper
 */
typedef enum {
  GST_PICK_DETECT_FEATURES_SIFT,
  GST_PICK_DETECT_FEATURES_ORB,
} GstPickDetectFeatures;

#define GST_TYPE_PICK_DETECT_FEATURES (gst_pick_detect_features_get_type())
GType gst_pick_detect_features_get_type(void);

#define GST_TYPE_PICK_DETECT (gst_pick_detect_get_type())
G_DECLARE_FINAL_TYPE(GstPickDetect, gst_pick_detect, GST, PICK_DETECT, GstVideoFilter)

GST_ELEMENT_REGISTER_DECLARE(pickdetect);

G_END_DECLS
