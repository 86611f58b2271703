# args: estimate {root}/scenarios/two_detectors.py --metric latency_p95_s
# exit: 2
# expect: --metric latency_p95_s: a run that detects no slip has no detection latency
"""A bad-input case: see tests/test_bad_inputs.py. A per-run statistic some runs lack has no mean over runs."""
