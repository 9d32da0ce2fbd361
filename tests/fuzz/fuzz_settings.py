"""How many cases each fuzz test draws: a fixed-seed sample in the default test run, any number with
``SSN_FUZZ_EXAMPLES=N`` (random seeds): ``SSN_FUZZ_EXAMPLES=2500 python -m pytest -m fuzz`` runs 12,500+ cases."""

import os

from hypothesis import HealthCheck, settings

EXAMPLES = int(os.environ.get("SSN_FUZZ_EXAMPLES", "0"))
FUZZ = settings(
    max_examples=EXAMPLES or 40,
    derandomize=not EXAMPLES,
    deadline=None,
    database=None,
    suppress_health_check=list(HealthCheck),
)
