# args: sweep-plot {case} -x hand_memory -y exposure_s -o {tmp}/p.png
# exit: 2
# expect: .csv
# untouched: {tmp}/p.png
"""A bad-input case: see tests/test_bad_inputs.py."""
