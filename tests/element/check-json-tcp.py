#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
# pipelines/serve-json-tcp.sh as it is: while it records the annotated clip, a client on
# 127.0.0.1 reads JSON lines from its tcpserversink; each must parse and hold the box.
#
#   check-json-tcp.py SCRIPT BUILD_DIR OUTPUT_DIR
import json
import os
import socket
import subprocess
import sys
import time

LINES = 5
TIMEOUT = 120  # seconds, for the whole test


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main():
    script, build_dir, out_dir = sys.argv[1:4]
    port = free_port()
    output = os.path.join(out_dir, "serve-json-tcp.webm")
    env = dict(os.environ, PICKDETECT_BUILD_DIR=build_dir, PORT=str(port), HOST="127.0.0.1",
               FRAMES="60")
    server = subprocess.Popen(["bash", script, output], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + TIMEOUT
    lines = []
    try:
        client = None
        while client is None:
            if server.poll() is not None:
                sys.exit("the pipeline ended before a client could connect: " + server.stderr.read())
            if time.monotonic() > deadline:
                sys.exit("could not connect to 127.0.0.1:%d" % port)
            try:
                client = socket.create_connection(("127.0.0.1", port), timeout=5)
            except OSError:
                time.sleep(0.05)
        client.settimeout(max(1.0, deadline - time.monotonic()))
        with client, client.makefile("r", encoding="utf-8") as stream:
            while len(lines) < LINES:
                line = stream.readline()
                if not line:
                    break
                lines.append(line)
        rc = server.wait(timeout=max(1.0, deadline - time.monotonic()))
    finally:
        if server.poll() is None:
            server.kill()
            server.wait()
    if rc != 0:
        sys.exit("serve-json-tcp.sh failed (%d): %s" % (rc, server.stderr.read()))
    if len(lines) < LINES:
        sys.exit("read %d lines from the server, expected %d" % (len(lines), LINES))
    frames = []
    for line in lines:
        if not line.endswith("\n"):
            sys.exit("a line without its newline: %r" % line[:80])
        obj = json.loads(line)
        frames.append(obj["frame"])
        if (obj["width"], obj["height"]) != (512, 384):
            sys.exit("frame size %sx%s, expected 512x384" % (obj["width"], obj["height"]))
        models = [i["model"] for i in obj["instances"]]
        if "box" not in models:
            sys.exit("frame %d: no box among %s" % (obj["frame"], models))
    if frames != list(range(frames[0], frames[0] + LINES)):
        sys.exit("frames out of order or missing: %s" % frames)
    if not os.path.getsize(output):
        sys.exit("the recording is empty")
    os.remove(output)
    print("read %d JSON lines (frames %s) from 127.0.0.1:%d while recording" % (LINES, frames, port))


main()
