"""The interpreter exits cleanly while a daemon thread is inside regbench.align or inside a
callable of regbench.run (issue 55, item 6: align ended in SIGABRT, exit 134).

When the interpreter finalises, CPython ends a daemon thread that asks for the interpreter lock
back (pthread_exit); pybind11's gil_scoped_release took it back in a noexcept destructor, where
that unwind is std::terminate, and pybind11's call of a Python function dropped references
without a thread state on the way (a fatal Python error). Such a thread is now parked (named
regbench-parked) until the process exits."""
import os
import subprocess
import sys
import textwrap

import pytest

PRELUDE = textwrap.dedent("""
    import os, sys, threading, time, types
    import numpy as np
    import regbench

    # The thread keeps the interpreter lock until it gives it up inside the call: the main
    # thread, waiting for `inside` and then for the lock, goes on only once the call is running.
    # (Not after a NumPy operation of the thread: NumPy releases the lock in loops over large
    # arrays.)
    sys.setswitchinterval(100)
    inside = threading.Event()
    comm = []
    wake_r, wake_w = os.pipe()

    class WaitsForTheThread:
        # Freed with the module that alone holds it, when the finalising interpreter empties
        # sys.modules (__main__'s globals stay alive: the thread's function holds them): wakes
        # the thread where it waits for that, then waits, the lock released, until the thread is
        # parked (or has ended).
        def __init__(self, comm):
            self.comm, self.sleep, self.write = comm, time.sleep, os.write

        def name(self):
            try:
                with open(self.comm) as f:
                    return f.read().strip()
            except FileNotFoundError:
                return "ended"

        def __del__(self):
            self.write(1, b"waiting for the thread\\n")
            self.write(wake_w, b"x")
            while self.name() not in ("regbench-parked", "ended"):
                self.sleep(0.01)
            self.write(1, self.name().encode() + b"\\n")

    def exit_while_inside(work):
        threading.Thread(target=work, daemon=True).start()
        inside.wait()
        sys.modules["waits_for_the_thread"] = holder = types.ModuleType("waits_for_the_thread")
        holder.waits = WaitsForTheThread(comm[0])
        print("main thread exits", flush=True)

    def entered():
        comm.append("/proc/self/task/%d/comm" % threading.get_native_id())
        inside.set()
""")

ALIGN = PRELUDE + textwrap.dedent("""
    rng = np.random.default_rng(0)
    source = rng.standard_normal((3000, 3))
    target = source + 0.01

    def work():
        entered()
        # About a second of dense CPD: it outlasts the main thread's way to finalisation.
        regbench.align(source, target, "cpd", params={"e_step": "dense", "maxiter": 50})
        os.write(1, b"the call returned before the interpreter finalised\\n")

    exit_while_inside(work)
""")

RUN = PRELUDE + textwrap.dedent("""
    def blocks(source, target):
        entered()
        os.read(wake_r, 1)  # returns once the interpreter finalises
        return np.eye(4)

    def work():
        regbench.run(sys.argv[1], [blocks], sys.argv[2])
        os.write(1, b"the run returned before the interpreter finalised\\n")

    exit_while_inside(work)
""")


@pytest.mark.parametrize("script", ["align", "run"])
def test_a_daemon_thread_inside_a_call_at_interpreter_exit(pairs_path, tmp_path, script):
    env = dict(os.environ, OMP_WAIT_POLICY="PASSIVE", OMP_NUM_THREADS="1")
    code = ALIGN if script == "align" else RUN
    proc = subprocess.run([sys.executable, "-c", code, pairs_path, str(tmp_path / "out.jsonl")],
                          capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "main thread exits\nwaiting for the thread\nregbench-parked\n"
    assert proc.stderr == ""
