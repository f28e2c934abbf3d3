"""The workbench's OpenAPI schema, fuzzed with schemathesis: every operation gets generated
requests, valid by the schema and not (wrong types, out-of-range numbers, missing fields,
strings over their limits), and every answer must hold to the API's contract:

- never a 5xx;
- every error (4xx) is JSON ``{"error": "..."}``, one line, no traceback;
- the status code, content type and body are what the schema documents for the operation.

Documents are described family by family in the schema (server/schema.py), so the valid ones
reach the mechanisms and the scene, drag, study and export code, not only the parser's first
refusal. Sample counts the schema allows up to 4096 are drawn smaller here (only within the
valid range) to keep the run to seconds; the limits themselves are tested, at and over each
value, in test_server_limits.py.
"""

from __future__ import annotations

import json
import tempfile

import pytest
import schemathesis
from hypothesis import HealthCheck, settings
from schemathesis import checks

from linkwright.server import create_app

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

EXAMPLES = 20  # per operation (positive and negative together): about 350 requests

# An atlas of the smallest size the workbench builds, so that the match's first call is quick.
_app = create_app(tempfile.mkdtemp(prefix="linkwright-fuzz-"))
_app.state.atlas_count = 100

_config = schemathesis.Config.from_dict(
    {
        # The schema's examples (real documents, so the mechanisms run) and Hypothesis's fuzzing;
        # not the coverage phase, whose boundary cases number in the hundreds per operation (the
        # limit tests take the boundaries one by one instead).
        "phases": {
            "coverage": {"enabled": False},
            "stateful": {"enabled": False},
        },
        "generation": {"mode": "all", "max-examples": EXAMPLES},
    }
)
schema = schemathesis.openapi.from_asgi("/openapi.json", _app, config=_config)

# The schema cannot say everything a document must be (joints that exist, pivots that differ,
# a linkage that assembles), so a request valid by the schema may still be refused 422: the
# positive_data_acceptance check does not apply. Everything else must hold.
CHECKS = [
    checks.not_a_server_error,
    checks.status_code_conformance,
    checks.content_type_conformance,
    checks.response_schema_conformance,
    checks.response_headers_conformance,
    checks.negative_data_rejection,
]

_CHEAP = {"samples": 48, "count": 3}


def _cheaper(body: object) -> None:
    """Valid sample and step counts drawn down to a few dozen (invalid ones stay as drawn)."""
    if not isinstance(body, dict):
        return
    for key, most in _CHEAP.items():
        value = body.get(key)
        if isinstance(value, int) and not isinstance(value, bool) and value >= 8:
            body[key] = min(value, most)


@schema.parametrize()
@settings(
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
)
def test_api_keeps_its_contract(case: schemathesis.Case) -> None:
    _cheaper(case.body)
    response = case.call()
    case.validate_response(response, checks=CHECKS)
    assert response.status_code < 500, response.text
    if response.status_code >= 400:
        assert response.headers.get("content-type", [""])[0].startswith("application/json")
        body = json.loads(response.content)
        assert set(body) == {"error"}, body
        message = body["error"]
        assert isinstance(message, str) and message.strip(), body
        assert "\n" not in message and "Traceback" not in message, message
