"""Client-server: starts pvserver on N MPI ranks, renders the APC scene from a pvpython client
and checks that the server's float image equals the pvbatch reference and that the client's
screenshot equals the pvbatch screenshot of the same scene.

    TestPvserver.py <ranks> <reference.vti> <reference.png> <workdir>

Run under an X server (ctest runs under xvfb-run); the environment carries APC_PLUGIN,
PYTHONPATH and the OMPI_* settings.
"""

import os
import socket
import subprocess
import sys
import time

import numpy
from PIL import Image

ranks, reference_vti, reference_png, workdir = sys.argv[1:5]
here = os.path.dirname(os.path.abspath(__file__))
os.makedirs(workdir, exist_ok=True)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


port = free_port()
server_log = open(os.path.join(workdir, "pvserver.log"), "w")
server = subprocess.Popen(
    ["mpirun", "--oversubscribe", "-np", ranks, "-x", "APC_PLUGIN", "-x", "PYTHONPATH",
     "-x", "DISPLAY", "pvserver", "--disable-xdisplay-test", "--server-port=%d" % port],
    stdout=server_log, stderr=subprocess.STDOUT, start_new_session=True)
verdict = 1
try:
    # Wait (bounded) until the server accepts connections.
    deadline = time.time() + 60
    while time.time() < deadline:
        with socket.socket() as s:
            if s.connect_ex(("127.0.0.1", port)) == 0:
                break
        if server.poll() is not None:
            raise RuntimeError("pvserver exited early (see pvserver.log)")
        time.sleep(0.5)
    else:
        raise RuntimeError("pvserver did not listen within 60 s")
    # The probe connection above counts as a client for some pvserver versions: give it a
    # moment to go back to listening.
    time.sleep(1.0)
    out_vti = os.path.join(workdir, "server.vti")
    out_png = os.path.join(workdir, "client.png")
    client = subprocess.run(
        ["pvpython", "--force-offscreen-rendering", os.path.join(here, "apc_scene.py"),
         "--scene", "puzzle", "--server", "localhost:%d" % port, "--out", out_vti,
         "--png", out_png, "--compare", reference_vti, "--tiled", os.path.join(workdir, "tiled"),
         "--client-timings", "--interactive", os.path.join(workdir, "interactive")],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=240)
    print(client.stdout)
    ok = client.returncode == 0 and "APC-TEST-PASSED" in client.stdout
    a = numpy.asarray(Image.open(out_png).convert("RGB"), dtype=int)
    b = numpy.asarray(Image.open(reference_png).convert("RGB"), dtype=int)
    if a.shape != b.shape:
        print("check failed: screenshot sizes differ", a.shape, b.shape)
        ok = False
    else:
        diff = int(numpy.abs(a - b).max())
        print("client screenshot vs pvbatch screenshot: max |diff| = %d/255" % diff)
        # Both are the same float image blended and captured by ParaView; allow one 8-bit
        # step for the client's image delivery.
        if diff > 1:
            print("check failed: the client's screenshot differs from pvbatch's")
            ok = False
    verdict = 0 if ok else 1
finally:
    try:
        os.killpg(server.pid, 15)
    except ProcessLookupError:
        pass
    try:
        server.wait(timeout=20)
    except subprocess.TimeoutExpired:
        os.killpg(server.pid, 9)
print("APC-TEST-PASSED" if verdict == 0 else "APC-TEST-FAILED")
sys.exit(verdict)
