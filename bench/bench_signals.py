"""Issue 22, item 5: a signal that comes just after FreeCADCmd exits, while ``aplan export-freecad`` reads the
bundle back (trimesh's imports, which catch ``BaseException``), must end the command with 128 + N, one line,
no bundle. Each try exports the truck, waits until FreeCADCmd has come and gone, waits 0.1 s more, sends the
signal, and prints the exit status, whether a bundle was left, a traceback seen, and the time from the
signal to the exit.

Run: ``.venv/bin/python bench/bench_signals.py [SIGINT|SIGTERM] [TRIES]`` (about 40 s a try on a loaded
machine; needs FreeCAD and ../shared).
"""
from __future__ import annotations

import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TRUCK = ROOT.parent / "shared" / "models" / "toy_truck" / "asm_cement_mixer_truck.FCStd"


def _children(pid: int) -> list[str]:
    return subprocess.run(["pgrep", "-P", str(pid)], capture_output=True, text=True).stdout.split()


def main() -> None:
    signum = getattr(signal, sys.argv[1]) if len(sys.argv) > 1 else signal.SIGINT
    tries = int(sys.argv[2]) if len(sys.argv) > 2 else 7
    folder = Path(tempfile.mkdtemp(prefix="aplan-signals-"))
    for k in range(tries):
        out = folder / f"b{k}"
        process = subprocess.Popen(["prlimit", f"--as={6 * 2 ** 30}", "--", sys.executable, "-m", "planner",
                                    "export-freecad", str(TRUCK), "-o", str(out)], cwd=ROOT,
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        seen = False
        while process.poll() is None:
            children = _children(process.pid)
            seen = seen or bool(children)
            if seen and not children:  # FreeCADCmd has exited: the bundle is being read back
                break
            time.sleep(0.01)
        time.sleep(0.1)
        sent = process.poll() is None
        if sent:
            process.send_signal(signum)
        began = time.perf_counter()
        _, err = process.communicate(timeout=600)
        text = err.decode()
        print(f"try {k}: {'signalled' if sent else 'ended before the signal'}, exit {process.returncode}, "
              f"{'a bundle' if out.exists() else 'no bundle'}, {'a traceback' if 'Traceback' in text else 'no traceback'}, "
              f"exit {time.perf_counter() - began:.1f} s after the signal: {text.strip().splitlines()[-1:]}",
              flush=True)
    shutil.rmtree(folder)


if __name__ == "__main__":
    main()
