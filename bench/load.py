"""Workbench under load: N requests at concurrency C on loopback, with zero errors (issue 10).

Run as ``python bench/load.py [--requests 2000] [--concurrency 32] [--seed 0]``. A real server
(uvicorn, as ``linkwright serve`` starts it, through :class:`linkwright.server.local.
LocalServer`) runs in this process's thread over a fresh data directory; ``--url`` aims at a
server already running instead. The client is one asyncio loop (httpx) keeping ``C`` requests
in flight, drawn at random (seeded) from what the page sends:

======================================  ======  ==========================================
request                                 share   what
======================================  ======  ==========================================
GET /api/health                          10 %    the transport's floor
GET /api/families                        10 %    the family menu
GET /api/examples/{name}                 15 %    one of the bundled examples
POST /api/scene                          30 %    a four-bar, slider-crank, spherical four-bar
                                                 or Jansen's leg, 120 samples, diagrams
POST /api/drag                           10 %    a four-bar's coupler point moved
POST /api/library                        10 %    a save under a new name
GET /api/library                          8 %    the library list
GET /api/library/{id}                     7 %    one saved entry loaded
======================================  ======  ==========================================

It prints the requests, the concurrency, the errors by status (any answer but 200 is one, and
so is a request that fails), the throughput, and p50/p95/p99/max latency per endpoint and
overall; it exits with status 1 on any error. The client shares the process (and its GIL)
with the server, so the latencies are an upper bound on what a separate client would see.

**The hostile mix** (issue 20) runs after it by default (``--mix normal|hostile|both``): a
real ``linkwright serve`` in a child process, its memory capped (``--memory-gib``, by
``setrlimit``), meets for ``--seconds`` at once

- slow clients (``--slow``, default 300): half send a request's headers a line every two
  seconds, half send whole headers and then a body a few bytes at a time (slowloris); each
  reconnects when the server drops it;
- the quadratic body: 33 ``[`` then 2 MB of ``\"`` (once 35 s of a frozen server per 64 KB),
  sent again and again;
- expensive requests (``--expensive`` clients, default 4): a geared five-bar's pivot study at
  ratio 64, 4,096 samples and 50 steps, and its scene at ratio 1000;
- a cheap scene now and then, as a person at the page would send;
- a prober asking ``GET /api/health`` every 50 ms throughout.

It prints health's p50/p95/max and what every other client was answered, the server's peak
memory and open files, and exits with status 1 if any health answer took over a second or
failed, or the server died.
"""

from __future__ import annotations

import argparse
import asyncio
import concurrent.futures
import contextlib
import os
import platform
import random
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import httpx
import numpy as np

from linkwright.io import document_to_dict, load_example
from linkwright.server.local import LocalServer

SCENE_EXAMPLES = ("crank-rocker", "offset-slider-crank", "paper000-fig6-crank-rocker", "jansen-leg")
EXAMPLE_NAMES = ("crank-rocker", "double-crank", "jansen-leg", "paper000-fig8-sixbar")
SCENE_SAMPLES = 120
TIMEOUT_S = 120.0
KEEPALIVE_S = 1.0
"""How long the client keeps an idle connection: well under uvicorn's keep-alive (5 s). With
httpx's default (also 5 s) a request can leave on a connection the server is closing at that
moment, a race of HTTP/1.1 keep-alive that a browser answers by sending the request again; this
bench would count it as an error (seen once in four runs of 2,000 requests on a loaded machine,
and every run with the server's keep-alive cut to 0.3 s)."""

MIX: tuple[tuple[str, float], ...] = (
    ("GET /api/health", 0.10),
    ("GET /api/families", 0.10),
    ("GET /api/examples/{name}", 0.15),
    ("POST /api/scene", 0.30),
    ("POST /api/drag", 0.10),
    ("POST /api/library", 0.10),
    ("GET /api/library", 0.08),
    ("GET /api/library/{id}", 0.07),
)
"""Each endpoint and its share of the requests."""


@dataclass
class Record:
    endpoint: str
    status: int | str  # the HTTP status, or the name of the exception a request failed with
    ms: float
    detail: str = ""  # what a failed request answered, or its exception's message


@dataclass
class LoadReport:
    """What one run measured: every request's endpoint, status and latency."""

    requests: int
    concurrency: int
    seconds: float
    records: list[Record] = field(default_factory=list)

    @property
    def errors(self) -> Counter[str]:
        """Failed requests by status (or exception name)."""
        return Counter(str(r.status) for r in self.records if r.status != 200)

    @property
    def throughput(self) -> float:
        return len(self.records) / self.seconds if self.seconds > 0 else float("nan")

    def latencies(self, endpoint: str | None = None) -> np.ndarray:
        return np.array([r.ms for r in self.records if endpoint in (None, r.endpoint)])


def _plan(n: int, seed: int) -> list[str]:
    """``n`` endpoints drawn from :data:`MIX` (seeded, so two runs send the same requests)."""
    rng = random.Random(seed)
    names = [name for name, _ in MIX]
    weights = [w for _, w in MIX]
    return rng.choices(names, weights=weights, k=n)


class _Client:
    """The requests of the mix, over one httpx client."""

    def __init__(self, http: httpx.AsyncClient, seed: int) -> None:
        self.http = http
        self.rng = random.Random(seed + 1)
        self.docs = {name: document_to_dict(load_example(name)) for name in SCENE_EXAMPLES}
        self.saved: list[int] = []
        self.count = 0

    async def setup(self) -> None:
        """One library entry to load before any save has happened."""
        r = await self.http.post(
            "/api/library",
            json={"name": "load seed", "document": self.docs["crank-rocker"], "overwrite": True},
        )
        r.raise_for_status()
        self.saved.append(int(r.json()["id"]))

    async def send(self, endpoint: str) -> httpx.Response:
        rng = self.rng
        if endpoint == "GET /api/health":
            return await self.http.get("/api/health")
        if endpoint == "GET /api/families":
            return await self.http.get("/api/families")
        if endpoint == "GET /api/examples/{name}":
            return await self.http.get(f"/api/examples/{rng.choice(EXAMPLE_NAMES)}")
        if endpoint == "POST /api/scene":
            doc = self.docs[rng.choice(SCENE_EXAMPLES)]
            body = {"document": doc, "samples": SCENE_SAMPLES, "at": None, "diagrams": True}
            return await self.http.post("/api/scene", json=body)
        if endpoint == "POST /api/drag":
            to = [1.0 + rng.uniform(-0.3, 0.3), 3.0 + rng.uniform(-0.3, 0.3)]
            body = {"document": self.docs["crank-rocker"], "joint": "P", "to": to, "at": 30.0}
            return await self.http.post("/api/drag", json=body)
        if endpoint == "POST /api/library":
            self.count += 1
            doc = self.docs[rng.choice(SCENE_EXAMPLES)]
            r = await self.http.post(
                "/api/library", json={"name": f"load {self.count}", "document": doc}
            )
            if r.status_code == 200:
                self.saved.append(int(r.json()["id"]))
            return r
        if endpoint == "GET /api/library":
            return await self.http.get("/api/library")
        if endpoint == "GET /api/library/{id}":
            return await self.http.get(f"/api/library/{rng.choice(self.saved)}")
        raise ValueError(f"endpoint: unknown {endpoint!r}")


async def _run(url: str, requests: int, concurrency: int, seed: int) -> LoadReport:
    plan = _plan(requests, seed)
    limits = httpx.Limits(
        max_connections=concurrency,
        max_keepalive_connections=concurrency,
        keepalive_expiry=KEEPALIVE_S,
    )
    async with httpx.AsyncClient(base_url=url, limits=limits, timeout=TIMEOUT_S) as http:
        client = _Client(http, seed)
        await client.setup()
        queue: asyncio.Queue[str] = asyncio.Queue()
        for endpoint in plan:
            queue.put_nowait(endpoint)
        records: list[Record] = []

        async def worker() -> None:
            while True:
                try:
                    endpoint = queue.get_nowait()
                except asyncio.QueueEmpty:
                    return
                started = time.perf_counter()
                detail = ""
                try:
                    response = await client.send(endpoint)
                    await response.aread()
                    status: int | str = response.status_code
                    if status != 200:
                        detail = response.text[:200]
                except httpx.HTTPError as exc:
                    status, detail = type(exc).__name__, f"{exc!r} at {time.time():.3f}"
                ms = 1e3 * (time.perf_counter() - started)
                records.append(Record(endpoint, status, ms, detail))

        started = time.perf_counter()
        await asyncio.gather(*(worker() for _ in range(concurrency)))
        seconds = time.perf_counter() - started
    return LoadReport(requests, concurrency, seconds, records)


def run_load(url: str, requests: int = 2_000, concurrency: int = 32, seed: int = 0) -> LoadReport:
    """Send ``requests`` requests of the mix to the workbench at ``url``, ``concurrency`` at a
    time, and report every one."""
    if requests < 1 or concurrency < 1:
        raise ValueError("requests and concurrency must be at least 1")
    return _run_sync(_run(url, requests, concurrency, seed))


def _run_sync(coroutine):
    """``asyncio.run`` here, or in a thread of its own where this thread already runs an event
    loop (Playwright's sync API keeps one running for a whole test session)."""
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        return asyncio.run(coroutine)
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        return pool.submit(asyncio.run, coroutine).result()


def run_local(requests: int = 2_000, concurrency: int = 32, seed: int = 0) -> LoadReport:
    """:func:`run_load` against a fresh :class:`LocalServer` over a scratch data directory."""
    with tempfile.TemporaryDirectory(prefix="linkwright-load-") as data, LocalServer(data) as url:
        return run_load(url, requests, concurrency, seed)


def format_report(report: LoadReport, where: str) -> str:
    """The report as a table (milliseconds)."""
    lines = [
        f"linkwright workbench load test ({where})",
        f"requests {len(report.records):,}, concurrency {report.concurrency}, "
        f"{report.seconds:.2f} s, throughput {report.throughput:,.0f} requests/s",
        "",
        f"{'endpoint':<28}{'n':>6}{'errors':>8}{'p50':>9}{'p95':>9}{'p99':>9}{'max':>9}",
    ]

    def row(label: str, endpoint: str | None) -> str:
        ms = report.latencies(endpoint)
        errors = sum(
            1 for r in report.records if endpoint in (None, r.endpoint) and r.status != 200
        )
        p50, p95, p99 = np.percentile(ms, [50, 95, 99]) if ms.size else (np.nan,) * 3
        return (
            f"{label:<28}{ms.size:>6}{errors:>8}{p50:>9.1f}{p95:>9.1f}{p99:>9.1f}"
            f"{(ms.max() if ms.size else np.nan):>9.1f}"
        )

    for endpoint, _ in MIX:
        lines.append(row(endpoint, endpoint))
    lines.append(row("overall", None))
    errors = report.errors
    lines += [
        "",
        "errors by status: "
        + (", ".join(f"{k} × {v}" for k, v in sorted(errors.items())) if errors else "none"),
    ]
    failed = [r for r in report.records if r.status != 200]
    lines += [f"  {r.endpoint}: {r.status} {r.detail}" for r in failed[:5]]
    return "\n".join(lines)


# --------------------------------------------------------------------------------------------
# The hostile mix (issue 20)
# --------------------------------------------------------------------------------------------

HEALTH_LIMIT_MS = 1_000.0
"""The longest a health answer may take while the server is attacked."""

PROBE_EVERY_S = 0.05
QUADRATIC = b"[" * 33 + b'\\"' * 999_000
"""33 ``[`` then 2 MB of escaped quotes: a string never closed, nested one level too deep."""


def _geared(ratio: float) -> dict:
    doc = document_to_dict(load_example("geared-fivebar"))
    doc["mechanism"]["ratio"] = ratio
    return doc


EXPENSIVE: tuple[tuple[str, str, dict], ...] = (
    (
        "study ratio 64",
        "/api/study",
        {"document": _geared(64.0), "pivot": "A0", "samples": 4096, "count": 50, "step": 0.01},
    ),
    ("scene ratio 1000", "/api/scene", {"document": _geared(1000.0)}),
)
"""Requests whose cost the limits on their sizes do not bound (561 bytes took 85–96 s and
4 GB; 497 bytes took 114 s), unless the server estimates their cost before it starts."""


@dataclass
class HostilePlan:
    """What the hostile mix sends, for how long."""

    seconds: float = 20.0
    slow: int = 300
    expensive: int = 4


@dataclass
class HostileReport:
    """What the hostile mix measured: every health probe, and every other answer by client."""

    plan: HostilePlan
    seconds: float
    health: list[Record] = field(default_factory=list)
    answers: list[Record] = field(default_factory=list)  # endpoint is the client's name
    slow_dropped: int = 0  # slow connections the server closed
    slow_opened: int = 0
    server_alive: bool = True
    server_peak_mib: float | None = None
    server_max_files: int | None = None

    @property
    def health_ms(self) -> np.ndarray:
        return np.array([r.ms for r in self.health])

    @property
    def ok(self) -> bool:
        """Every health probe answered 200 within :data:`HEALTH_LIMIT_MS`, and the server lived."""
        return (
            bool(self.health)
            and all(r.status == 200 and r.ms <= HEALTH_LIMIT_MS for r in self.health)
            and self.server_alive
        )


async def _prober(url: str, stop: asyncio.Event, out: list[Record]) -> None:
    limits = httpx.Limits(max_connections=1, keepalive_expiry=KEEPALIVE_S)
    async with httpx.AsyncClient(base_url=url, limits=limits, timeout=30.0) as http:
        while not stop.is_set():
            started = time.perf_counter()
            try:
                r = await http.get("/api/health")
                status: int | str = r.status_code
                detail = "" if r.status_code == 200 else r.text[:200]
            except httpx.HTTPError as exc:
                status, detail = type(exc).__name__, repr(exc)
            out.append(
                Record("GET /api/health", status, 1e3 * (time.perf_counter() - started), detail)
            )
            await asyncio.sleep(PROBE_EVERY_S)


async def _slow_client(host: str, port: int, k: int, stop: asyncio.Event, report: HostileReport):
    """One slow client: headers a line every two seconds (even k), or whole headers and then a
    body a few bytes at a time (odd k); reconnecting whenever the server drops it."""
    while not stop.is_set():
        try:
            reader, writer = await asyncio.open_connection(host, port)
        except OSError:
            await asyncio.sleep(0.5)
            continue
        report.slow_opened += 1
        try:
            if k % 2 == 0:
                writer.write(f"POST /api/scene HTTP/1.1\r\nHost: {host}\r\n".encode())
            else:
                writer.write(
                    f"POST /api/scene HTTP/1.1\r\nHost: {host}\r\n"
                    "Content-Type: application/json\r\nContent-Length: 100000\r\n\r\n{".encode()
                )
            while not stop.is_set():
                await writer.drain()
                try:
                    data = await asyncio.wait_for(reader.read(1024), 2.0)
                except TimeoutError:
                    writer.write(b"X-Slow: 1\r\n" if k % 2 == 0 else b" ")
                    continue
                if not data or reader.at_eof():
                    report.slow_dropped += 1
                    break
        except (OSError, ConnectionError):
            report.slow_dropped += 1
        finally:
            writer.close()
            with contextlib.suppress(OSError, ConnectionError):
                await writer.wait_closed()


async def _repeat(
    url: str, name: str, send, stop: asyncio.Event, out: list[Record], pause: float = 0.0
) -> None:
    """Send a request again and again until ``stop``, recording each answer under ``name``."""
    limits = httpx.Limits(max_connections=1, keepalive_expiry=KEEPALIVE_S)
    async with httpx.AsyncClient(base_url=url, limits=limits, timeout=300.0) as http:
        while not stop.is_set():
            started = time.perf_counter()
            try:
                r = await send(http)
                status: int | str = r.status_code
                detail = r.text[:2000] if r.status_code != 200 else ""
            except httpx.HTTPError as exc:
                status, detail = type(exc).__name__, repr(exc)[:160]
            out.append(Record(name, status, 1e3 * (time.perf_counter() - started), detail))
            if pause:
                await asyncio.sleep(pause)


async def _hostile(url: str, plan: HostilePlan, report: HostileReport) -> None:
    parts = httpx.URL(url)
    host, port = parts.host, parts.port or 80
    stop = asyncio.Event()
    tasks = [asyncio.create_task(_prober(url, stop, report.health))]
    # The slow clients first, so that the others meet a server whose connections are taken.
    tasks += [
        asyncio.create_task(_slow_client(host, port, k, stop, report)) for k in range(plan.slow)
    ]
    await asyncio.sleep(0.5)
    json_type = {"content-type": "application/json"}

    async def quadratic(http: httpx.AsyncClient) -> httpx.Response:
        return await http.post("/api/scene", content=QUADRATIC, headers=json_type)

    tasks.append(
        asyncio.create_task(_repeat(url, "quadratic body", quadratic, stop, report.answers))
    )
    for k in range(plan.expensive):
        name, path, body = EXPENSIVE[k % len(EXPENSIVE)]

        async def expensive(http: httpx.AsyncClient, path=path, body=body) -> httpx.Response:
            return await http.post(path, json=body)

        tasks.append(asyncio.create_task(_repeat(url, name, expensive, stop, report.answers)))
    cheap = {"document": document_to_dict(load_example("crank-rocker")), "samples": 120}

    async def scene(http: httpx.AsyncClient) -> httpx.Response:
        return await http.post("/api/scene", json=cheap)

    tasks.append(
        asyncio.create_task(_repeat(url, "cheap scene", scene, stop, report.answers, pause=0.2))
    )
    await asyncio.sleep(plan.seconds)
    stop.set()
    # The prober and the cheap clients end at once; requests still in flight are abandoned.
    await asyncio.sleep(0.2)
    for task in tasks:
        task.cancel()
    await asyncio.gather(*tasks, return_exceptions=True)


def run_hostile(url: str, plan: HostilePlan | None = None, pid: int | None = None) -> HostileReport:
    """Run the hostile mix against the workbench at ``url`` (module docstring); with ``pid``
    (the server's process), its peak memory and open files are read from ``/proc``."""
    plan = plan or HostilePlan()
    report = HostileReport(plan, 0.0)
    files: list[int] = []
    watching = True

    def watch() -> None:
        while watching and pid is not None:
            with contextlib.suppress(OSError):
                files.append(len(os.listdir(f"/proc/{pid}/fd")))
            time.sleep(0.25)

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    started = time.perf_counter()
    try:
        _run_sync(_hostile(url, plan, report))
    finally:
        watching = False
        watcher.join(2)
    report.seconds = time.perf_counter() - started
    if files:
        report.server_max_files = max(files)
    if pid is not None:
        with contextlib.suppress(OSError):
            status = Path(f"/proc/{pid}/status").read_text()
            peak = next(line for line in status.splitlines() if line.startswith("VmHWM:"))
            report.server_peak_mib = int(peak.split()[1]) / 1024
    try:
        report.server_alive = httpx.get(f"{url}/api/health", timeout=10).status_code == 200
    except httpx.HTTPError:
        report.server_alive = False
    return report


# The child caps its own address space before it imports anything (no preexec_fn: this process
# may have threads, and a fork with threads may deadlock before exec).
_CAPPED = (
    "import resource, runpy, sys; cap = int(sys.argv.pop(1)); "
    "resource.setrlimit(resource.RLIMIT_AS, (cap, cap)); "
    "runpy.run_module('linkwright', run_name='__main__')"
)


@contextlib.contextmanager
def serve_capped(data_dir: str | os.PathLike[str], memory_bytes: int) -> Iterator[tuple[str, int]]:
    """``linkwright serve`` in a child process on a free loopback port, its address space capped
    at ``memory_bytes`` (an allocation past it fails inside the server, which answers 500,
    instead of the machine running out); yields (url, pid) once it answers, and stops it."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = int(s.getsockname()[1])
    # Few malloc arenas: each thread's own would reserve 64 MB of address space for nothing.
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "MALLOC_ARENA_MAX": "2"}
    cmd = [sys.executable, "-c", _CAPPED, str(memory_bytes), "serve", "--port", str(port)]
    cmd += ["--data-dir", os.fspath(data_dir)]
    with tempfile.TemporaryFile() as log:
        proc = subprocess.Popen(
            cmd, stdout=subprocess.DEVNULL, stderr=log, stdin=subprocess.DEVNULL, env=env
        )
        url = f"http://127.0.0.1:{port}"
        try:
            deadline = time.monotonic() + 60
            while True:
                if proc.poll() is not None:
                    log.seek(0)
                    raise RuntimeError(f"the server did not start: {log.read()[-400:]!r}")
                with contextlib.suppress(httpx.HTTPError):
                    if httpx.get(f"{url}/api/health", timeout=2).status_code == 200:
                        break
                if time.monotonic() > deadline:
                    raise RuntimeError("the server did not answer within 60 s")
                time.sleep(0.1)
            yield url, proc.pid
        finally:
            proc.terminate()
            try:
                proc.wait(15)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(15)


def run_hostile_local(
    plan: HostilePlan | None = None, memory_bytes: int = 4 << 30
) -> HostileReport:
    """:func:`run_hostile` against a capped child server over a scratch data directory."""
    with (
        tempfile.TemporaryDirectory(prefix="linkwright-hostile-") as data,
        serve_capped(data, memory_bytes) as (url, pid),
    ):
        return run_hostile(url, plan, pid)


def format_hostile(report: HostileReport, where: str) -> str:
    """The hostile mix's report: health's latency, then every other client's answers."""
    ms = report.health_ms
    p50, p95 = np.percentile(ms, [50, 95]) if ms.size else (np.nan, np.nan)
    worst = ms.max() if ms.size else np.nan
    bad = [r for r in report.health if r.status != 200]
    plan = report.plan
    lines = [
        f"linkwright workbench under the hostile mix ({where})",
        f"{report.seconds:.1f} s: {plan.slow} slow clients, the quadratic body, "
        f"{plan.expensive} clients of expensive requests, a cheap scene every 0.2 s",
        "",
        f"GET /api/health every {1e3 * PROBE_EVERY_S:.0f} ms: {ms.size} probes, p50 {p50:.1f} ms, "
        f"p95 {p95:.1f} ms, max {worst:.1f} ms; failed {len(bad)}; "
        f"over {HEALTH_LIMIT_MS:.0f} ms: {int((ms > HEALTH_LIMIT_MS).sum())}",
        f"slow connections: {report.slow_opened} opened, "
        f"{report.slow_dropped} closed by the server",
    ]
    for name in dict.fromkeys(r.endpoint for r in report.answers):
        rows = [r for r in report.answers if r.endpoint == name]
        statuses = Counter(str(r.status) for r in rows)
        t = np.array([r.ms for r in rows])
        lines.append(
            f"{name + ':':<18}{len(rows):>5} answers ("
            + ", ".join(f"{k} × {v}" for k, v in sorted(statuses.items()))
            + f"), p50 {np.percentile(t, 50):.0f} ms, max {t.max():.0f} ms"
        )
        odd = next((r for r in rows if r.status not in (200, 422, 503)), None)
        if odd is not None:
            lines.append(f"{'':<18}e.g. {odd.status} {odd.detail[:160]}")
    if report.server_peak_mib is not None:
        lines.append(
            f"server: peak memory {report.server_peak_mib:,.0f} MiB, "
            f"at most {report.server_max_files} open files"
        )
    lines.append(f"server alive after: {'yes' if report.server_alive else 'NO'}")
    lines += [f"  health failed: {r.status} {r.detail}" for r in bad[:3]]
    lines.append("PASS" if report.ok else "FAIL")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--requests", type=int, default=2_000, help="requests in all")
    parser.add_argument("--concurrency", type=int, default=32, help="requests in flight")
    parser.add_argument("--seed", type=int, default=0, help="seed of the request mix")
    parser.add_argument("--url", help="a running workbench (default: start one here)")
    parser.add_argument(
        "--mix", choices=("normal", "hostile", "both"), default="both", help="which mix to run"
    )
    parser.add_argument("--seconds", type=float, default=20.0, help="the hostile mix's length")
    parser.add_argument("--slow", type=int, default=300, help="slow clients in the hostile mix")
    parser.add_argument(
        "--expensive", type=int, default=4, help="clients sending expensive requests"
    )
    parser.add_argument(
        "--memory-gib", type=float, default=4.0, help="the hostile mix's server memory cap"
    )
    args = parser.parse_args(argv)
    machine = f"{platform.machine()}, Python {platform.python_version()}"
    failed = False
    if args.mix in ("normal", "both"):
        if args.url:
            report = run_load(args.url, args.requests, args.concurrency, args.seed)
            where = args.url
        else:
            report = run_local(args.requests, args.concurrency, args.seed)
            where = "loopback, uvicorn in this process"
        print(format_report(report, f"{where}; {machine}"))
        failed |= bool(report.errors)
    if args.mix in ("hostile", "both"):
        if args.mix == "both":
            print()
        plan = HostilePlan(seconds=args.seconds, slow=args.slow, expensive=args.expensive)
        if args.url:
            hostile = run_hostile(args.url, plan)
            where = args.url
        else:
            hostile = run_hostile_local(plan, memory_bytes=int(args.memory_gib * 2**30))
            where = f"linkwright serve in a child process, memory capped at {args.memory_gib:g} GiB"
        print(format_hostile(hostile, f"{where}; {machine}"))
        failed |= not hostile.ok
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
