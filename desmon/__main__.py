from desmon.cli.program import run_program

run_program()
