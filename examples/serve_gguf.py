#!/usr/bin/env python3
"""Serve a GGUF file (a model `examples/finetune.py` wrote, or any other) with llama.cpp's
OpenAI-compatible server from the `xllamacpp` package, on 127.0.0.1, until Ctrl-C:

    python examples/serve_gguf.py tuned/model.gguf --port 8080 &
    coherent run native --task 3 --base-url http://127.0.0.1:8080/v1 --model tuned

Two slots (`--parallel`): PEFA's assigner and executor each keep the prompt prefix it
shares with its own last question in the server's cache. The first line printed is the
server's address (`--port 0`: any free port).
"""

from __future__ import annotations

import argparse
import signal
import sys


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("model", help="the GGUF file")
    p.add_argument("--port", type=int, default=8080)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--parallel", type=int, default=2, help="requests served at once, each with its slot of the context")
    p.add_argument("--ctx", type=int, default=8192, help="tokens of context per slot")
    args = p.parse_args()
    import xllamacpp

    params = xllamacpp.CommonParams()
    params.model.path = args.model
    params.cpuparams.n_threads = args.threads
    params.cpuparams_batch.n_threads = args.threads
    params.hostnames = ["127.0.0.1"]
    params.port = args.port
    params.n_parallel = args.parallel
    params.n_ctx = args.ctx * args.parallel
    server = xllamacpp.Server(params)
    print(server.listening_address, flush=True)
    signal.sigwait({signal.SIGINT, signal.SIGTERM})
    del server
    return 0


if __name__ == "__main__":
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    sys.exit(main())
