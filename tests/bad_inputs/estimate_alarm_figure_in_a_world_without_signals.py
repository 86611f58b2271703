# args: estimate {root}/scenarios/two_detectors.py --metric false_alarms
# exit: 2
# expect: --metric false_alarms counts the detectors' alarms, and this world renders no sensor signals
# expect: or give the scenario's World signals=True
"""A bad-input case: see tests/test_bad_inputs.py. two_detectors' World renders no signals:
no run could raise an alarm."""
