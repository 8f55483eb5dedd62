#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Prints the instances pickdetect finds, one line per instance, read from the buffers' metas.

A pad probe on pickdetect's src pad reads each buffer's GstVideoRegionOfInterestMeta (one per
instance) and its "pick-instance" parameters: nothing but GStreamer's own Python bindings
(python3-gst-1.0, gir1.2-gst-plugins-base-1.0) is needed.

    pipelines/read-instances.py [--model MODEL] [--frames N] [INPUT]

INPUT is a picture (shown --frames times) or a video file; it defaults to OpenCV's
box_in_scene.png with box.png as the model. The uninstalled plugin is found through
GST_PLUGIN_PATH=<builddir>/gst, or PICKDETECT_BUILD_DIR=<builddir>, or --build-dir.

Output, one line per instance:
    frame=0 pts=0:00:00.000000000 roi=0 model=box center=(187.03,223.92) angle=8.41 scale=0.537
    score=0.885 matches=78 visibility=1.00 covered=yes pickable=no pick-order=0
    grasp=(187.03,223.92) bbox=89,161+196x138
(on one line) and "frame=N instances=0" for a frame without any. (The box in box_in_scene.png
is covered: another package lies on its edge.)
"""
import argparse
import os
import sys

from pickdetect_plugin import add_build_dir_argument, init_gstreamer

DATA = "/usr/share/doc/opencv-doc/examples/data"
PICTURES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("input", nargs="?", default=os.path.join(DATA, "box_in_scene.png"),
                        help="picture or video file (default: OpenCV's box_in_scene.png)")
    parser.add_argument("--model", default=os.path.join(DATA, "box.png"),
                        help="model file (.yml), picture or model set, or several separated "
                             "by commas (default: OpenCV's box.png)")
    parser.add_argument("--frames", type=int, default=3,
                        help="how many frames to make of a picture (default: 3)")
    add_build_dir_argument(parser)
    args = parser.parse_args()

    Gst = init_gstreamer(args.build_dir)
    import gi
    gi.require_version("GstVideo", "1.0")
    from gi.repository import GLib, GstVideo

    source = "filesrc name=src ! decodebin"
    if args.input.lower().endswith(PICTURES):
        source += " ! imagefreeze num-buffers=%d" % args.frames
    pipeline = Gst.parse_launch(
        source + " ! videoconvert ! pickdetect name=detect post-messages=false ! fakesink")
    pipeline.get_by_name("src").set_property("location", args.input)
    pipeline.get_by_name("detect").set_property("model", args.model)

    roi_api = GstVideo.VideoRegionOfInterestMeta.get_info().api
    frame = [0]
    first_id = [0]  # The lowest ROI id of the last frame: where to look from in the next one.

    def on_buffer(pad, info):
        buf = info.get_buffer()
        n = buf.get_n_meta(roi_api)
        found = 0
        roi_id = first_id[0]
        lowest = None
        # ROI ids are unique within a buffer. With tracking (the default) pickdetect gives each
        # ROI its instance's track id, which only grows; without, it numbers them from 0.
        while found < n and roi_id < first_id[0] + n + 1024:
            roi = GstVideo.buffer_get_video_region_of_interest_meta_id(buf, roi_id)
            roi_id += 1
            if roi is None:
                continue
            found += 1
            lowest = roi.id if lowest is None else min(lowest, roi.id)
            s = roi.get_param("pick-instance")
            if s is None:
                continue  # Someone else's region of interest.
            d = lambda name: s.get_double(name)[1]
            i = lambda name: s.get_int(name)[1]
            has_track, track_id = s.get_uint64("track-id")
            print("frame=%d pts=%s roi=%d model=%s center=(%.2f,%.2f) angle=%.2f scale=%.3f "
                  "score=%.3f matches=%d visibility=%.2f covered=%s pickable=%s pick-order=%d "
                  "grasp=(%.2f,%.2f) bbox=%d,%d+%dx%d points=%d%s%s"
                  % (frame[0], Gst.TIME_ARGS(buf.pts), roi.id, GLib.quark_to_string(roi.roi_type),
                     d("center-x"), d("center-y"), d("angle"), d("scale"), d("score"),
                     i("matches"), d("visibility"),
                     "yes" if s.get_boolean("covered")[1] else "no",
                     "yes" if s.get_boolean("pickable")[1] else "no", i("pick-order"),
                     d("grasp-x"), d("grasp-y"), roi.x, roi.y, roi.w, roi.h,
                     len(list(s.get_value("points"))) // 2,
                     " track=%d" % track_id if has_track else "",
                     " view=%s" % s.get_string("view") if s.get_string("view") else ""))
        if lowest is not None:
            first_id[0] = lowest
        if found == 0:
            print("frame=%d pts=%s instances=0" % (frame[0], Gst.TIME_ARGS(buf.pts)))
        sys.stdout.flush()
        frame[0] += 1
        return Gst.PadProbeReturn.OK

    pipeline.get_by_name("detect").get_static_pad("src").add_probe(
        Gst.PadProbeType.BUFFER, on_buffer)

    if pipeline.set_state(Gst.State.PLAYING) == Gst.StateChangeReturn.FAILURE:
        msg = pipeline.get_bus().pop_filtered(Gst.MessageType.ERROR)
        pipeline.set_state(Gst.State.NULL)
        sys.exit("error: %s" % (msg.parse_error()[0].message if msg else "could not start"))
    msg = pipeline.get_bus().timed_pop_filtered(Gst.CLOCK_TIME_NONE,
                                                Gst.MessageType.EOS | Gst.MessageType.ERROR)
    pipeline.set_state(Gst.State.NULL)
    if msg.type == Gst.MessageType.ERROR:
        err, debug = msg.parse_error()
        sys.exit("error: %s (%s)" % (err.message, debug))


if __name__ == "__main__":
    main()
