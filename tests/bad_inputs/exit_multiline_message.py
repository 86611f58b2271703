# args: replay {case}
# exit: 2
# expect: RuntimeError: line one line two
"""A bad-input case: see tests/test_bad_inputs.py."""
raise RuntimeError('line one\nline two')
