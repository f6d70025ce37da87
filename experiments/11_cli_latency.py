"""How long the command line takes to answer without rendering (BENCHMARKS.md, "Command
line start-up").

`hairjax --help`, `hairjax render --help` and `hairjax --version` parse their arguments
before anything heavy is imported (`hairjax/cli/_parser.py` is standard library only, and
`import hairjax` is lazy, `hairjax/__init__.pyi`); `import hairjax; hairjax.render` is
shown beside them as the cost a command that renders pays first (JAX and the package).
Each is a fresh interpreter, timed from start to exit; medians of `--repeats` runs.

    python experiments/11_cli_latency.py                # 11 runs each
    python experiments/11_cli_latency.py --repeats 3    # the test suite's size
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import time

CASES = {
    "hairjax --help": ["-c", "import sys; from hairjax.cli import main; sys.exit(main(['--help']))"],
    "hairjax render --help": [
        "-c",
        "import sys; from hairjax.cli import main; sys.exit(main(['render', '--help']))",
    ],
    "hairjax --version": ["-c", "import sys; from hairjax.cli import main; sys.exit(main(['--version']))"],
    "import hairjax; hairjax.render": ["-c", "import hairjax; hairjax.render"],
}


def _time(argv: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run([sys.executable, *argv], check=True, capture_output=True)
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=11, help="runs per case (their median)")
    parser.add_argument("--json", help="also write the medians (seconds) as JSON")
    args = parser.parse_args(argv)
    medians = {}
    for name, case in CASES.items():
        _time(case)  # warm the file cache
        medians[name] = statistics.median(_time(case) for _ in range(args.repeats))
    width = max(len(n) for n in medians)
    print(f"command-line start-up, medians of {args.repeats} fresh interpreters ({sys.executable})")
    for name, seconds in medians.items():
        print(f"{name:<{width}}  {seconds * 1000:8.1f} ms")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(medians, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
