"""Run every benchmark (``benchmarks/bench_*.py``) in turn: ``python benchmarks/run_all.py``.

Each benchmark prints its own table, including ratios against a baseline measured in the
same run. Pass ``--quick`` to shrink the work.
"""

import subprocess
import sys
from pathlib import Path

here = Path(__file__).resolve().parent
rc = 0
for script in sorted(here.glob("bench_*.py")):
    print(f"\n===== {script.name} =====", flush=True)
    rc |= subprocess.call([sys.executable, str(script), *sys.argv[1:]])
sys.exit(rc)
