#!/usr/bin/env python3
"""ctest Serve.PythonClient: examples/ssl_client.py drives a robot of `twinsim serve
--lockstep` to a pose over the loopback (free ports, no multicast), once over the
league's simulation protocol (with one camera, and with four staggered cameras, each
numbering its own frames), once over grSim's and once through the synchronous
interface over TCP; Ctrl-C then ends the server. Usage: ssl_client_test.py TWINSIM SOURCE_DIR BUILD_DIR"""
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time


def free_port():
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def drive(twinsim, source, build, protocol, cameras=False):
    """Serves serve_2v2 in lockstep and drives blue 1 to a pose over `protocol`."""
    out = tempfile.mkdtemp(prefix="twinsim_serve_client_")
    scene = os.path.join(source, "scenes", "serve_2v2_cameras.yaml" if cameras else "serve_2v2.yaml")
    control, blue, yellow, vision, grsim = (free_port() for _ in range(5))
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        sync = s.getsockname()[1]
    mode = (["--sync-port", str(sync)] if protocol == "sync" else
            ["--lockstep", "--teams", "blue", "--grsim-port", str(grsim)])
    server = subprocess.Popen(
        [twinsim, "serve", scene, "--backend", "analytic"] + mode +
        ["--control-port", str(control), "--blue-port", str(blue), "--yellow-port", str(yellow),
         "--vision-port", str(vision), "--out", out, "-q"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    port = {"grsim": grsim, "sync": sync}.get(protocol, blue)
    try:
        if protocol == "sync":  # the server's TCP port is open once it has started
            for _ in range(100):
                if server.poll() is not None:
                    sys.exit(f"server exited {server.returncode}: {server.stderr.read().decode()}")
                try:
                    socket.create_connection(("127.0.0.1", sync), timeout=1).close()
                    break
                except OSError:
                    time.sleep(0.05)
        client = subprocess.run(
            [sys.executable, os.path.join(source, "examples", "ssl_client.py"), "--vision-port", str(vision),
             "--protocol", protocol, "--team-port", str(port), "--id", "1",
             "--x", "0.5", "--y", "-1.0", "--theta-deg", "90", "--frames", "900",
             "--proto-py", os.path.join(build, "proto_py")],
            capture_output=True, text=True, timeout=120)
    finally:
        server.send_signal(signal.SIGINT)
        stdout, stderr = server.communicate(timeout=60)
    print(client.stdout, client.stderr)
    if client.returncode != 0:
        sys.exit(f"client failed ({client.returncode})")
    if server.returncode != 0:
        sys.exit(f"server exited {server.returncode}: {stderr.decode()}")
    log = open(os.path.join(out, "trajectory_blue1.csv")).read().splitlines()
    if log[0] != "t,x,y,theta,vx_cmd,vy_cmd,omega_cmd" or len(log) < 30:
        sys.exit(f"unexpected log: {log[:3]} ({len(log)} lines)")
    x, y = (float(v) for v in log[-1].split(",")[1:3])
    if abs(x - 0.5) > 0.05 or abs(y + 1.0) > 0.05:
        sys.exit(f"blue1 logged at ({x}, {y}), not at the target")
    print(f"ok ({protocol}{', four cameras' if cameras else ''}): {len(log) - 1} frames logged, blue1 at ({x:.3f}, {y:.3f})")


def main():
    twinsim, source, build = sys.argv[1:4]
    for protocol in ("league", "grsim", "sync"):
        drive(twinsim, source, build, protocol)
    drive(twinsim, source, build, "league", cameras=True)


if __name__ == "__main__":
    main()
