#!/usr/bin/python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""Counts the objects crossing a line on a belt, one line of output per counted object.

pickdetect tracks every instance (tracking=true, its default) and, with count-line set, posts a
"pickdetect-count" element message each time a track crosses the line: each object is counted
once, also when it stops on the line, jitters across it or is hidden on it for a moment. This
program prints those messages; only GStreamer's own Python bindings are needed.

    pipelines/count-objects.py --model MODEL --line X1,Y1,X2,Y2 [--fps N] INPUT

INPUT is a video file, or a numbered picture sequence as multifilesrc reads it
(scenes/%04d.jpg, at --fps frames a second). The uninstalled plugin is found through
GST_PLUGIN_PATH=<builddir>/gst, or PICKDETECT_BUILD_DIR=<builddir>, or --build-dir. At camera
rate on large frames, start it with glibc's freed memory kept in the process:
GLIBC_TUNABLES=glibc.malloc.mmap_threshold=33554432:glibc.malloc.trim_threshold=1073741824
(docs/performance.md, "The process's heap").

Output, one line per counted object, then the totals:
    counted model=box track=3 count=1 total=1 time=0:00:00.833333333
    total=7 box=7
"""
import argparse
import sys

from pickdetect_plugin import add_build_dir_argument, init_gstreamer


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("input", help="a video file, or a picture sequence such as scenes/%%04d.jpg")
    parser.add_argument("--model", required=True, help="model file(s) or picture(s), as pickdetect's model")
    parser.add_argument("--line", required=True, help="the count line x1,y1,x2,y2 in frame pixels")
    parser.add_argument("--fps", type=int, default=30,
                        help="frames per second of a picture sequence (default: 30)")
    add_build_dir_argument(parser)
    args = parser.parse_args()

    Gst = init_gstreamer(args.build_dir)

    if "%" in args.input:
        source = ("multifilesrc name=src caps=image/jpeg,framerate=%d/1 ! decodebin" % args.fps
                  if args.input.lower().endswith((".jpg", ".jpeg")) else
                  "multifilesrc name=src caps=image/png,framerate=%d/1 ! decodebin" % args.fps)
    else:
        source = "filesrc name=src ! decodebin"
    pipeline = Gst.parse_launch(
        source + " ! videoconvert ! pickdetect name=detect post-messages=false ! fakesink")
    pipeline.get_by_name("src").set_property("location", args.input)
    detect = pipeline.get_by_name("detect")
    detect.set_property("model", args.model)
    detect.set_property("count-line", args.line)

    totals = {}
    bus = pipeline.get_bus()
    if pipeline.set_state(Gst.State.PLAYING) == Gst.StateChangeReturn.FAILURE:
        msg = bus.pop_filtered(Gst.MessageType.ERROR)
        pipeline.set_state(Gst.State.NULL)
        sys.exit("error: %s" % (msg.parse_error()[0].message if msg else "could not start"))
    status = 0
    while True:
        msg = bus.timed_pop_filtered(Gst.CLOCK_TIME_NONE, Gst.MessageType.ELEMENT |
                                     Gst.MessageType.EOS | Gst.MessageType.ERROR)
        if msg.type == Gst.MessageType.ERROR:
            err, debug = msg.parse_error()
            sys.stderr.write("error: %s\n%s\n" % (err.message, debug or ""))
            status = 1
            break
        if msg.type == Gst.MessageType.EOS:
            break
        s = msg.get_structure()
        if s is None or s.get_name() != "pickdetect-count":
            continue
        model = s.get_string("model")
        totals[model] = s.get_int("count")[1]
        print("counted model=%s track=%d count=%d total=%d time=%s"
              % (model, s.get_uint64("track-id")[1], s.get_int("count")[1],
                 s.get_int("total")[1], Gst.TIME_ARGS(s.get_uint64("running-time")[1])))
        sys.stdout.flush()
    pipeline.set_state(Gst.State.NULL)
    print("total=%d%s" % (sum(totals.values()),
                          "".join(" %s=%d" % kv for kv in sorted(totals.items()))))
    return status


if __name__ == "__main__":
    sys.exit(main())
