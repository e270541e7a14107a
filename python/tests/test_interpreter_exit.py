"""The interpreter exits cleanly while a daemon thread is inside regbench.align (issue 55, item 6:
it ended in SIGABRT, exit 134).

When the interpreter finalises, CPython ends a daemon thread that asks for the interpreter lock
back (pthread_exit); pybind11's gil_scoped_release took it back in a noexcept destructor, where
that unwind is std::terminate."""
import os
import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent("""
    import os, sys, threading, time
    import numpy as np
    import regbench

    # The thread keeps the interpreter lock until align releases it in C++: the main thread,
    # waiting for `inside` and then for the lock, goes on only once the call is running.
    sys.setswitchinterval(1e6)
    rng = np.random.default_rng(0)
    source = rng.standard_normal((3000, 3))
    inside = threading.Event()
    task = []

    def work():
        task.append("/proc/self/task/%d" % threading.get_native_id())
        inside.set()
        # About a second of dense CPD: it outlasts the main thread's way to finalisation.
        regbench.align(source, source + 0.01, "cpd", params={"e_step": "dense", "maxiter": 50})
        os.write(1, b"the call returned before the interpreter finalised\\n")

    class WaitsForTheThread:
        # Torn down with __main__, while the interpreter finalises: waits, the lock released,
        # until the thread, back from align, has been ended by CPython.
        def __init__(self):
            self.exists, self.sleep = os.path.exists, time.sleep

        def __del__(self):
            while self.exists(task[0]):
                self.sleep(0.01)

    waits = WaitsForTheThread()
    threading.Thread(target=work, daemon=True).start()
    inside.wait()
    print("main thread exits", flush=True)
""")


def test_a_daemon_thread_inside_align_at_interpreter_exit():
    env = dict(os.environ, OMP_WAIT_POLICY="PASSIVE", OMP_NUM_THREADS="1")
    proc = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                          env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == "main thread exits\n"
    assert proc.stderr == ""
