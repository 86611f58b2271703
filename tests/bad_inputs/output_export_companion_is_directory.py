# args: analyze {root}/scenarios/coffee_shift.py -p faults=False --horizon 60 --no-progress --export {tmp}/m.tra
# exit: 2
# expect: --export {tmp}/m.tra would write {tmp}/m.sta, which is a directory: remove it or export under another name
# mkdir: {tmp}/m.sta
# untouched: {tmp}/m.tra
# untouched: {tmp}/m.lab
# untouched: {tmp}/m.srew
"""A bad-input case: see tests/test_bad_inputs.py. A PRISM export writes four files; one of them is a directory:
refused before any work, and none of the others is written (they used to be replaced one by one at the end)."""
