# args: sweep-plot {tmp}/t.csv -x hand_memory -y exposure -o {tmp}/p.png
# copy: {data} {tmp}/t.csv
# exit: 2
# expect: -y exposure: the table has no such column
# expect: did you mean exposure_s
# untouched: {tmp}/p.png
"""A bad-input case: see tests/test_bad_inputs.py."""
