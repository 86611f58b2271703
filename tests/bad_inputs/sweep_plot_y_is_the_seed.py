# args: sweep-plot {tmp}/t.csv -x hand_memory -y seed -o {tmp}/p.png
# copy: {data} {tmp}/t.csv
# exit: 2
# expect: -y seed: a run's bookkeeping (point, seed_index, seed), not a figure of the run
# untouched: {tmp}/p.png
"""A bad-input case: see tests/test_bad_inputs.py. The seeds had been drawn as a figure, with a
confidence interval of their mean."""
