"""Long calls release the GIL, and Ctrl-C (SIGINT) stops them cleanly:
KeyboardInterrupt soon after, the interpreter still usable."""

import signal
import subprocess
import sys
import threading
import time

import petrinav as pn

# The child installs Python's own SIGINT handler (KeyboardInterrupt): a
# process started in the background by a non-interactive shell (as CI may
# start the tests) inherits SIGINT ignored, and Python then keeps it so.
SCRIPT = """
import signal, sys, time, petrinav as pn
signal.signal(signal.SIGINT, signal.default_int_handler)
what = sys.argv[1]
net = pn.family("kanban", 5) if what == "solve" else pn.load(sys.argv[2])
start = time.time()
try:
    print("ready", flush=True)
    if what == "solve":
        net.solve()
    else:
        net.simulate(time=1e12, seed=1, max_wall=None)
    print("finished", flush=True)
except KeyboardInterrupt:
    print(f"interrupted {time.time() - start:.1f}", flush=True)
    # The interpreter goes on, and so does petrinav.
    print(pn.family("kanban", 1).solve().solver, flush=True)
"""


def interrupt(args, after_s=1.5):
    p = subprocess.Popen(
        [sys.executable, "-c", SCRIPT, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    first = p.stdout.readline().strip()
    assert first == "ready", (first, p.stderr.read())
    time.sleep(after_s)
    p.send_signal(signal.SIGINT)
    sent = time.time()
    out, err = p.communicate(timeout=120)
    return out.split("\n"), time.time() - sent, p.returncode, err


def test_ctrl_c_stops_a_long_solve():
    # Kanban N = 5: 2.5 million states, some 10 s or more to generate and solve.
    lines, waited, code, err = interrupt(["solve"])
    assert code == 0, err
    assert lines[0].startswith("interrupted"), (lines, err)
    # Soon: at the next checkpoint (an expansion round, a compilation
    # stage, a BiCGSTAB sweep), not at the end (some 10 s or more).
    assert waited < 8, f"{waited:.1f} s between Ctrl-C and the end"
    assert lines[1] == "direct-gth"  # a later solve works


def test_ctrl_c_stops_a_long_simulation(root):
    lines, waited, code, err = interrupt(["simulate", str(root / "models/supervisor.toml")])
    assert code == 0, err
    assert lines[0].startswith("interrupted"), (lines, err)
    assert waited < 8, f"{waited:.1f} s between Ctrl-C and the end"


def test_a_solve_releases_the_gil():
    net = pn.family("kanban", 1, params={"N": 3})
    ticks = []
    stop = threading.Event()

    def count():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    start = time.perf_counter()
    net.solve()
    end = time.perf_counter()
    stop.set()
    t.join()
    during = [x for x in ticks if start < x < end]
    # The other thread ran meanwhile (it would be frozen if the GIL were held).
    assert end - start > 0.05
    assert len(during) >= 10, f"{len(during)} ticks in {end - start:.2f} s"
