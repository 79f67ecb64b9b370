"""A worker process of :mod:`drakedeburr.pool`: ``python -m drakedeburr.pool_worker``.

Reads pickled tasks ``(function, args)`` from stdin and writes pickled ``("ok", result)`` or
``("error", message)`` to the stdout it was started with, until stdin closes. Anything else the
process writes to stdout goes to stderr instead, so it cannot break the stream. A plain process
(not ``multiprocessing``): it never imports the caller's main script.
"""

from __future__ import annotations

import os
import pickle
import sys

#: the stream the replies go to (kept here so that a test can write a broken reply)
STATE: dict = {}


def main() -> None:
    stream_out = STATE["out"] = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # stray output to stderr
    sys.stdout = sys.stderr
    stream_in = sys.stdin.buffer
    while True:
        try:
            fn, args = pickle.load(stream_in)
        except EOFError:
            return
        try:
            reply = ("ok", fn(*args))
        except Exception as exc:  # reported to the caller, which plans the window itself
            reply = ("error", f"{type(exc).__name__}: {exc}")
        pickle.dump(reply, stream_out, protocol=pickle.HIGHEST_PROTOCOL)
        stream_out.flush()


if __name__ == "__main__":
    main()
