#!/usr/bin/env python3
"""A stub OpenAI-compatible chat completions server for throughput measurements
(docs/scale.md): every answer comes after a fixed delay, at most N requests are served at
once (the others wait their turn, as on a model server with N slots), and each answer is
valid for the role that asks (the first robot, its first action), so that episodes run
to their step budget.

    python3 scripts/stub-openai.py --port 8000 --delay 0.2 --slots 64

Standard library only (asyncio, HTTP/1.1 with keep-alive). On stop (Ctrl-C, SIGTERM) it
prints what it served as one JSON line: requests, the most in flight at once, the
seconds from the first to the last, and the CPU seconds it used.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import resource
import signal
import time


class Stats:
    def __init__(self) -> None:
        self.connections: set[asyncio.StreamWriter] = set()
        self.requests = 0
        self.in_flight = 0
        self.most_in_flight = 0
        self.first: float | None = None
        self.last = 0.0


def answer(body: dict) -> str:
    """A valid answer to the role asking: the first robot and its first action."""
    fmt = body.get("response_format", {}).get("json_schema", {})
    props = fmt.get("schema", {}).get("properties", {})
    if fmt.get("name") == "proposal":
        content = {"reasoning": "go", "robot": props["robot"]["enum"][0], "subtask": "the first thing you can"}
    else:
        # A dialogue's speaker may have no action of its own yet: its list is empty.
        actions = props.get("action", {}).get("enum") or ["none"]
        content = {"action": actions[0], "subtask_complete": False, "note": ""}
    return json.dumps(
        {
            "choices": [{"index": 0, "message": {"role": "assistant", "content": json.dumps(content)}, "finish_reason": "stop"}],
            "usage": {"prompt_tokens": 100, "completion_tokens": 10},
        }
    )


async def serve_connection(
    reader: asyncio.StreamReader, writer: asyncio.StreamWriter, slots: asyncio.Semaphore, delay: float, stats: Stats
) -> None:
    stats.connections.add(writer)
    try:
        while True:
            head = await reader.readuntil(b"\r\n\r\n")
            length = 0
            for line in head.decode("latin-1").split("\r\n"):
                name, _, value = line.partition(":")
                if name.strip().lower() == "content-length":
                    length = int(value)
            body = json.loads(await reader.readexactly(length)) if length else {}
            async with slots:
                stats.in_flight += 1
                stats.most_in_flight = max(stats.most_in_flight, stats.in_flight)
                stats.first = stats.first or time.monotonic()
                await asyncio.sleep(delay)
                stats.in_flight -= 1
            reply = answer(body).encode()
            writer.write(
                b"HTTP/1.1 200 OK\r\ncontent-type: application/json\r\ncontent-length: "
                + str(len(reply)).encode()
                + b"\r\n\r\n"
                + reply
            )
            await writer.drain()
            stats.requests += 1
            stats.last = time.monotonic()
    except (asyncio.IncompleteReadError, ConnectionError):
        pass
    finally:
        stats.connections.discard(writer)
        writer.close()


async def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=8000)
    parser.add_argument("--delay", type=float, default=0.2, help="seconds before each answer")
    parser.add_argument("--slots", type=int, default=64, help="requests served at once")
    args = parser.parse_args()
    stats = Stats()
    slots = asyncio.Semaphore(args.slots)
    server = await asyncio.start_server(
        lambda r, w: serve_connection(r, w, slots, args.delay, stats), args.host, args.port, limit=1 << 22
    )
    stop = asyncio.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        asyncio.get_running_loop().add_signal_handler(sig, stop.set)
    print(f"listening on http://{args.host}:{server.sockets[0].getsockname()[1]}/v1", flush=True)
    async with server:
        await stop.wait()
        # Kept-alive connections end here, so that no handler is left waiting.
        for writer in list(stats.connections):
            writer.close()
        while stats.connections:
            await asyncio.sleep(0.01)
    seconds = stats.last - stats.first if stats.first else 0.0
    usage = resource.getrusage(resource.RUSAGE_SELF)
    summary = {
        "requests": stats.requests,
        "most_in_flight": stats.most_in_flight,
        "seconds": round(seconds, 3),
        "cpu_seconds": round(usage.ru_utime + usage.ru_stime, 3),
    }
    print(json.dumps(summary), flush=True)


if __name__ == "__main__":
    asyncio.run(main())
