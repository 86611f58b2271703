# args: estimate {root}/scenarios/coffee_handover.py --no-signals --metric slips_missed --at-least 1 --no-progress
# exit: 2
# expect: --metric slips_missed counts the detectors' alarms, and this world renders no sensor signals
# expect: drop --no-signals
"""A bad-input case: see tests/test_bad_inputs.py. It was refused after a run, as "a run
gave no number for it; choose another metric", which named neither the offender nor the fix."""
