#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
# pipelines/publish-mqtt.sh as it is, against a real mosquitto broker started here on
# 127.0.0.1 at a free port; mosquitto_sub reads the messages back, each a JSON line with the
# box. Bounded in time; the broker is stopped at the end, whatever happened.
#
#   check-json-mqtt.py SCRIPT BUILD_DIR WORK_DIR
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time

FRAMES = 12
MESSAGES = 6
TOPIC = "pickdetect/test/instances"


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for_port(port, process, seconds):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if process.poll() is not None:
            return False
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return True
        except OSError:
            time.sleep(0.05)
    return False


def main():
    script, build_dir, work_dir = sys.argv[1:4]
    for tool in ("mosquitto", "mosquitto_sub", "mosquitto_pub"):
        if not shutil.which(tool) and not os.path.exists("/usr/sbin/" + tool):
            sys.exit("%s not found (Debian: mosquitto, mosquitto-clients)" % tool)
    broker_bin = shutil.which("mosquitto") or "/usr/sbin/mosquitto"
    port = free_port()
    folder = tempfile.mkdtemp(prefix="pickdetect-mqtt-", dir=work_dir)
    config = os.path.join(folder, "mosquitto.conf")
    with open(config, "w") as f:
        f.write("listener %d 127.0.0.1\nallow_anonymous true\npersistence false\n" % port)
    broker = subprocess.Popen([broker_bin, "-c", config], stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True)
    subscriber = None
    lines = []
    try:
        if not wait_for_port(port, broker, 10):
            why = broker.stderr.read() if broker.poll() is not None else "timeout"
            sys.exit("the broker did not listen on 127.0.0.1:%d: %s" % (port, why))
        # -C: leave after that many messages; -W: or after that many seconds. The subscription
        # is made before anything is published (-d prints the SUBACK; stdbuf makes its output
        # line-buffered, else the SUBACK would wait in its stdio buffer until it leaves).
        subscriber = subprocess.Popen(
            ["stdbuf", "-oL", "mosquitto_sub", "-h", "127.0.0.1", "-p", str(port), "-t", TOPIC,
             "-C", str(MESSAGES), "-W", "60", "-d"],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        while True:  # Debug lines until the SUBACK, then the messages.
            line = subscriber.stdout.readline()
            if not line:
                sys.exit("mosquitto_sub ended before subscribing")
            if "SUBACK" in line:
                break
        env = dict(os.environ, PICKDETECT_BUILD_DIR=build_dir, MQTT_HOST="127.0.0.1",
                   MQTT_PORT=str(port), MQTT_TOPIC=TOPIC, FRAMES=str(FRAMES))
        publisher = subprocess.run(["bash", script], env=env, capture_output=True, text=True,
                                   timeout=120)
        if publisher.returncode != 0:
            sys.exit("publish-mqtt.sh failed (%d): %s" % (publisher.returncode, publisher.stderr))
        out, _ = subscriber.communicate(timeout=90)
        lines = [l for l in out.splitlines() if l.startswith("{")]
    finally:
        if subscriber and subscriber.poll() is None:
            subscriber.kill()
            subscriber.wait()
        broker.terminate()
        try:
            broker.wait(timeout=10)
        except subprocess.TimeoutExpired:
            broker.kill()
            broker.wait()
        shutil.rmtree(folder, ignore_errors=True)
    if len(lines) != MESSAGES:
        sys.exit("received %d messages, expected %d" % (len(lines), MESSAGES))
    frames = []
    for line in lines:
        obj = json.loads(line)
        frames.append(obj["frame"])
        if not any(i["model"] == "box" and i["matches"] > 0 for i in obj["instances"]):
            sys.exit("frame %d: no box" % obj["frame"])
    if frames != list(range(MESSAGES)):
        sys.exit("frames %s, expected 0..%d in order" % (frames, MESSAGES - 1))
    print("received %d JSON messages through mosquitto on 127.0.0.1:%d" % (MESSAGES, port))


main()
