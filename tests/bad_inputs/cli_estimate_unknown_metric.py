# args: estimate {root}/scenarios/two_detectors.py --metric exposure
# exit: 2
# expect: --metric 'exposure': no such run metric
# expect: did you mean exposure_s?
# expect: slips_missed, false_alarms
"""A bad-input case: see tests/test_bad_inputs.py. A metric name that is not a run figure: the valid ones are listed."""
