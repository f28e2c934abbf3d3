"""The hostile mix of bench/load.py, short: a real ``linkwright serve`` in a child process,
its memory capped by ``setrlimit``, meets slow clients, the quadratic body and expensive
requests at once, and ``/api/health`` answers within a second throughout (issue 20).

Before the work queue, the linear body guard and the connection bounds, the quadratic body
alone froze every client for 35 s, and the expensive requests filled the thread pool that
health waited on.
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(
    not Path("/proc/self/status").exists(), reason="reads the server's memory from /proc"
)


def _load_module():
    path = Path(__file__).resolve().parents[1] / "bench" / "load.py"
    spec = importlib.util.spec_from_file_location("linkwright_bench_load_hostile", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def test_health_answers_within_a_second_under_the_hostile_mix() -> None:
    load = _load_module()
    plan = load.HostilePlan(seconds=5.0, slow=100, expensive=2)
    report = load.run_hostile_local(plan, memory_bytes=3 << 30)
    table = load.format_hostile(report, "test")
    assert report.ok, table
    assert report.health and max(r.ms for r in report.health) <= 1_000.0, table
    assert report.server_alive, table
    assert report.slow_opened >= plan.slow, table
    # Every answer the other clients got is the API's one-line JSON (a MemoryError inside the
    # capped server included), never a plain-text error.
    for r in report.answers:
        if isinstance(r.status, int) and r.status >= 400:
            assert set(json.loads(r.detail)) == {"error"}, (r.endpoint, r.status, r.detail)
    quadratic = [r for r in report.answers if r.endpoint == "quadratic body"]
    assert quadratic and all(r.status == 422 for r in quadratic), table
    assert report.server_max_files is not None and report.server_max_files < 1_024, table
