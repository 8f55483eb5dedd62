# SPDX-License-Identifier: LGPL-2.1-or-later
"""What the Python pipelines beside this file share: finding the pickdetect plugin.

The uninstalled plugin is found through GST_PLUGIN_PATH=<builddir>/gst, or
PICKDETECT_BUILD_DIR=<builddir>, or --build-dir; else in GStreamer's plugin folder after
`meson install`. Only GStreamer's own Python bindings are needed.
"""
import os
import sys


def add_build_dir_argument(parser):
    """Adds --build-dir (default: PICKDETECT_BUILD_DIR) to an argparse parser."""
    parser.add_argument("--build-dir", default=os.environ.get("PICKDETECT_BUILD_DIR"),
                        help="meson build folder holding gst/libgstpickdetect.so")


def init_gstreamer(build_dir):
    """Puts build_dir/gst (when given) first on GST_PLUGIN_PATH, initialises GStreamer and returns
    its Gst module; exits with a message when the pickdetect element is not found."""
    if build_dir:
        plugin_dir = os.path.join(os.path.abspath(build_dir), "gst")
        old = os.environ.get("GST_PLUGIN_PATH")
        os.environ["GST_PLUGIN_PATH"] = plugin_dir + (os.pathsep + old if old else "")

    import gi
    gi.require_version("Gst", "1.0")
    from gi.repository import Gst

    Gst.init(None)
    if Gst.ElementFactory.find("pickdetect") is None:
        sys.exit("pickdetect not found: set GST_PLUGIN_PATH=<builddir>/gst or "
                 "PICKDETECT_BUILD_DIR=<builddir>, or install the plugin (meson install)")
    return Gst
