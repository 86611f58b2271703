# args: sweep-plot {tmp}/t.csv -x hand_memory -y verdict -o {tmp}/p.png
# copy: {data} {tmp}/t.csv
# exit: 2
# expect: -y verdict: the column holds text
# untouched: {tmp}/p.png
"""A bad-input case: see tests/test_bad_inputs.py."""
