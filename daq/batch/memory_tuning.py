"""Keep freed memory in the process instead of handing it back to the kernel.

The fits allocate and free the same large temporaries (spectra of every hit for a
batch of damping matrices) hundreds of times. By default glibc returns such memory
to the kernel at each free (the top of the heap past M_TRIM_THRESHOLD, and blocks
over M_MMAP_THRESHOLD as their own mappings), and the next call faults it in again,
page by page. On a virtual machine that was most of the time: `daq fit --method
de` on a 5-hit run took 54 s, 19 s of it in the kernel; with freed memory kept,
30 s and 0.4 s. The cost is that a process keeps its peak heap until it exits,
which for a command or a worker process is what we want.

Linux with glibc only; elsewhere this does nothing.
"""

from __future__ import annotations

import ctypes
import sys

# mallopt(3) parameters.
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
#: glibc's largest allowed mmap threshold on 64-bit systems (DEFAULT_MMAP_THRESHOLD_MAX).
_MMAP_THRESHOLD_BYTES = 32 * 2**20
_TRIM_THRESHOLD_BYTES = 2**30


def _libc(use_errno: bool = False) -> ctypes.CDLL:
    """The C library this process runs on: dlopen(NULL), the process's own symbols,
    which on Linux include its libc. No search by name: ctypes.util.find_library runs
    ldconfig (a child process) on every command. Should dlopen(NULL) fail, the libc
    found by name as before; OSError if neither loads."""
    try:
        return ctypes.CDLL(None, use_errno=use_errno)
    except OSError:
        from ctypes.util import find_library

        return ctypes.CDLL(find_library("c") or "libc.so.6", use_errno=use_errno)


def keep_freed_memory() -> bool:
    """Tell glibc's malloc to keep freed memory; True if it accepted."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = _libc()
        mallopt = libc.mallopt
    except (OSError, AttributeError):  # musl and others have no mallopt
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    return bool(mallopt(_M_MMAP_THRESHOLD, _MMAP_THRESHOLD_BYTES)) and bool(
        mallopt(_M_TRIM_THRESHOLD, _TRIM_THRESHOLD_BYTES)
    )


# prctl(2): deliver this signal to the calling process when its parent dies.
_PR_SET_PDEATHSIG = 1
#: How often the fallback watchdog looks whether the parent is still there, s.
WATCHDOG_PERIOD_S = 0.5


def die_with_parent(parent_pid: int) -> bool:
    """End this (worker) process as soon as ``parent_pid``, its parent, is gone.

    Killing `daq analyze --all` (SIGKILL, a closed terminal) used to leave its pool's
    workers running for good: they wait on a pipe the other workers also hold open.
    On Linux prctl(PR_SET_PDEATHSIG, SIGKILL) has the kernel kill us with the parent;
    everywhere, a daemon thread also checks os.getppid() every WATCHDOG_PERIOD_S (the
    fallback where prctl is missing, and for a parent that died before the prctl).
    True if the kernel took the request."""
    import os
    import signal
    import threading
    import time

    def orphaned() -> bool:
        return os.getppid() != parent_pid

    def kill_self() -> None:
        os.kill(os.getpid(), signal.SIGKILL)

    armed = False
    if sys.platform.startswith("linux"):
        try:
            libc = _libc(use_errno=True)
            prctl = libc.prctl
            prctl.argtypes = (ctypes.c_int, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong)
            prctl.restype = ctypes.c_int
            armed = prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
        except (OSError, AttributeError):
            armed = False
    if orphaned():  # the parent died before the request: nobody will signal us
        kill_self()

    def watch() -> None:
        while not orphaned():
            time.sleep(WATCHDOG_PERIOD_S)
        kill_self()

    threading.Thread(target=watch, name="die-with-parent", daemon=True).start()
    return armed


def worker_setup(parent_pid: int) -> None:
    """ProcessPoolExecutor initializer of the batch commands' workers: keep freed
    memory (see above) and die with the parent ``parent_pid``."""
    keep_freed_memory()
    die_with_parent(parent_pid)
