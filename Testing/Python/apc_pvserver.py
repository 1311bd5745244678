"""A pvserver on N MPI ranks for the client-server tests: started on a free local port with the
APC plugin's environment, waited for (bounded), and stopped with its whole process group on
every exit path, so that a failing test never leaves MPI ranks behind.

    with PvServer(ranks, workdir) as server:      # server.url: "cs://localhost:<port>"
        subprocess.run(["pvpython", ..., "--server", server.address])

or server.start() ... server.stop() in a try/finally.

Its output goes to <workdir>/pvserver.log. Needs an X server (DISPLAY) like pvbatch.
"""

import os
import socket
import subprocess
import time


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class PvServer:
    def __init__(self, ranks, workdir, timeout=60):
        self.ranks = str(ranks)
        self.log_path = os.path.join(workdir, "pvserver.log")
        self.timeout = timeout
        self.port = free_port()
        self.process = None

    @property
    def address(self):
        return "localhost:%d" % self.port

    @property
    def url(self):
        return "cs://" + self.address

    def __enter__(self):
        return self.start()

    def start(self):
        log = open(self.log_path, "w")
        self.process = subprocess.Popen(
            ["mpirun", "--oversubscribe", "-np", self.ranks, "-x", "APC_PLUGIN", "-x",
             "PYTHONPATH", "-x", "DISPLAY", "pvserver", "--disable-xdisplay-test",
             "--server-port=%d" % self.port],
            stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            self._wait_until_listening()
        except BaseException:
            self.stop()
            raise
        return self

    def __exit__(self, *exception):
        self.stop()
        return False

    def _wait_until_listening(self):
        deadline = time.time() + self.timeout
        while time.time() < deadline:
            with socket.socket() as s:
                if s.connect_ex(("127.0.0.1", self.port)) == 0:
                    # The probe counts as a client for some pvserver versions: give it a
                    # moment to go back to listening.
                    time.sleep(1.0)
                    return
            if self.process.poll() is not None:
                raise RuntimeError("pvserver exited early (see %s)" % self.log_path)
            time.sleep(0.5)
        raise RuntimeError("pvserver did not listen within %d s" % self.timeout)

    def stop(self):
        if self.process is None:
            return
        try:
            os.killpg(self.process.pid, 15)
        except ProcessLookupError:
            pass
        try:
            self.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            os.killpg(self.process.pid, 9)
            self.process.wait()
        self.process = None
