"""Run every benchmark: ``python -m bench`` (or ``make bench``). Each prints its own figures."""

import importlib
import pkgutil
from pathlib import Path

for info in sorted(pkgutil.iter_modules([str(Path(__file__).parent)]), key=lambda m: m.name):
    if info.name.startswith("bench_"):
        print(f"== {info.name} ==", flush=True)
        importlib.import_module(f"bench.{info.name}").main()
        print(flush=True)
