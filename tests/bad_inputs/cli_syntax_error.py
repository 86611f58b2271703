# args: replay {case}
# exit: 2
# expect: syntax error
x = (
