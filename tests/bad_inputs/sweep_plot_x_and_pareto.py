# args: sweep-plot {tmp}/t.csv -x hand_memory --pareto hand_memory -y exposure_s -o {tmp}/p.png
# copy: {data} {tmp}/t.csv
# exit: 2
# expect: give either -x PARAMETER
# untouched: {tmp}/p.png
"""A bad-input case: see tests/test_bad_inputs.py."""
