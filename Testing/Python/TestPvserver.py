"""Client-server: starts pvserver on N MPI ranks, renders the APC scene from a pvpython client
and checks that the server's float image equals the pvbatch reference and that the client's
screenshot equals the pvbatch screenshot of the same scene.

    TestPvserver.py <ranks> <reference.vti> <reference.png> <workdir>

Run under an X server (ctest runs under xvfb-run); the environment carries APC_PLUGIN,
PYTHONPATH and the OMPI_* settings.
"""

import os
import subprocess
import sys

import numpy
from PIL import Image

from apc_pvserver import PvServer

ranks, reference_vti, reference_png, workdir = sys.argv[1:5]
here = os.path.dirname(os.path.abspath(__file__))
os.makedirs(workdir, exist_ok=True)


verdict = 1
with PvServer(ranks, workdir) as server:
    out_vti = os.path.join(workdir, "server.vti")
    out_png = os.path.join(workdir, "client.png")
    client = subprocess.run(
        ["pvpython", "--force-offscreen-rendering", os.path.join(here, "apc_scene.py"),
         "--scene", "puzzle", "--server", server.address, "--out", out_vti,
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
print("APC-TEST-PASSED" if verdict == 0 else "APC-TEST-FAILED")
sys.exit(verdict)
