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
"""

from __future__ import annotations

import argparse
import asyncio
import platform
import random
import sys
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field

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
    return asyncio.run(_run(url, requests, concurrency, seed))


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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--requests", type=int, default=2_000, help="requests in all")
    parser.add_argument("--concurrency", type=int, default=32, help="requests in flight")
    parser.add_argument("--seed", type=int, default=0, help="seed of the request mix")
    parser.add_argument("--url", help="a running workbench (default: start one here)")
    args = parser.parse_args(argv)
    if args.url:
        report = run_load(args.url, args.requests, args.concurrency, args.seed)
        where = args.url
    else:
        report = run_local(args.requests, args.concurrency, args.seed)
        where = "loopback, uvicorn in this process"
    machine = f"{platform.machine()}, Python {platform.python_version()}"
    print(format_report(report, f"{where}; {machine}"))
    return 1 if report.errors else 0


if __name__ == "__main__":
    sys.exit(main())
