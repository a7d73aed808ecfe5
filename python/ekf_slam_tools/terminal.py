"""Programs driven through a real pseudo-terminal, as a person at a keyboard
drives them (teleop, the guided calibration), for the rostests."""
import os
import pty
import select
import signal
import threading
import time


def wait_for(condition, timeout=10.0, period=0.05):
    """Polls `condition` until it holds or `timeout` seconds have passed;
    returns its last value."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(period)
    return condition()


class TerminalProgram:
    """`argv` run with a pseudo-terminal as its terminal; what it writes is
    collected by a thread (`text()`), keys go in with `type()`."""

    def __init__(self, argv):
        self.pid, self.fd = pty.fork()
        if self.pid == 0:  # the child
            os.execvp(argv[0], argv)
        self._lock = threading.Lock()
        self._chunks = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        while True:
            try:
                if not select.select([self.fd], [], [], 0.1)[0]:
                    continue
                data = os.read(self.fd, 4096)
            except OSError:  # the program ended: the terminal is gone
                return
            if not data:
                return
            with self._lock:
                self._chunks.append(data.decode("utf-8", "replace"))

    def text(self):
        with self._lock:
            return "".join(self._chunks)

    def type(self, keys):
        os.write(self.fd, keys.encode() if isinstance(keys, str) else keys)

    def wait_for_text(self, marker, timeout):
        return wait_for(lambda: marker in self.text(), timeout)

    def wait(self):
        """The exit status once the program ends."""
        _, status = os.waitpid(self.pid, 0)
        self.pid = None
        return os.WEXITSTATUS(status)

    def kill(self):
        if self.pid is not None:
            try:
                os.kill(self.pid, signal.SIGKILL)
                os.waitpid(self.pid, 0)
            except (ProcessLookupError, ChildProcessError):
                pass
            self.pid = None
