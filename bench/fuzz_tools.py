"""The tools' command lines under a long seeded fuzz (test/support/tool_fuzz.py; the tests
run a few dozen cases, this thousands): every case is checked as the test checks it (exit
status 0, 1 or 2; a failure one line under 300 characters naming the problem, never an
internal error or a traceback; nothing left behind), and the outcomes are tabled by tool
and by what the refusal said. A robustness run, not a timing: see docs/robustness.md.

    .venv/bin/python bench/fuzz_tools.py [--cases 1000] [--seed 1] [--valid 0.1]
"""

from __future__ import annotations

import argparse
import json
import re
import sys
import tempfile
import time
from collections import Counter, defaultdict
from pathlib import Path

from common import REPO, RESULTS, machine_info  # first: puts the checkout on sys.path

sys.path.insert(0, str(REPO))
from test.support.tool_fuzz import ToolFuzzer, check, prepare, run_case, snapshot  # noqa: E402


def kind(tool: str, status: int, stderr: str) -> str:
    """What the refusal was about, in a few words (the path or value left out)."""
    if status == 0:
        return "ok"
    line = next((x for x in stderr.splitlines() if ": error: " in x), stderr.strip()[:60])
    text = line.split(": error: ", 1)[-1]
    if text.startswith("argument "):
        text = re.sub(r"got .*", "got ...", text.split("; see --help")[0])
        return text.replace(": not a", ": not a").split(":", 1)[0] + ": " + text.split(": ", 1)[-1][:40]
    text = re.sub(r"^\S+?: ", "PATH: ", text)  # the path named first
    return re.sub(r"'[^']*'|\"[^\"]*\"|\d+(\.\d+)?(e[+-]?\d+)?", "_", text)[:70]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--valid", type=float, default=0.1, help="share of cases with no bad value")
    args = parser.parse_args()
    fuzzer = ToolFuzzer(args.seed, valid_share=args.valid)
    statuses: dict[str, Counter] = defaultdict(Counter)
    kinds: dict[str, Counter] = defaultdict(Counter)
    problems = []
    began = time.monotonic()
    with tempfile.TemporaryDirectory() as work:
        folder = Path(work)
        prepare(folder)
        for _ in range(args.cases):
            case = fuzzer.case()
            before = snapshot(folder)
            status, out, err = run_case(case, folder)
            after = snapshot(folder)
            problem = check(case, status, out, err, before, after)
            if problem:
                problems.append(f"{case.tool} {case.argv}: {problem}")
            statuses[case.tool][status] += 1
            kinds[case.tool][kind(case.tool, status, err)] += 1
            for name in sorted(set(after) - set(before), reverse=True):  # a success's outputs
                path = folder / name
                path.unlink() if path.is_file() else path.rmdir()
    print(f"{args.cases} cases, seed {args.seed}, {time.monotonic() - began:.0f} s; problems: {len(problems)}")
    print("\n| tool | cases | exit 0 | exit 1 | exit 2 | other |\n|---|---|---|---|---|---|")
    for tool, counts in sorted(statuses.items()):
        other = sum(v for k, v in counts.items() if k not in (0, 1, 2))
        print(f"| {tool} | {sum(counts.values())} | {counts[0]} | {counts[1]} | {counts[2]} | {other} |")
    print("\nrefusals by kind (most frequent first):")
    for tool, counts in sorted(kinds.items()):
        print(f"  {tool}:")
        for text, count in counts.most_common(12):
            print(f"    {count:5d}  {text}")
    for problem in problems[:20]:
        print("PROBLEM", problem)
    RESULTS.mkdir(exist_ok=True)
    result = {
        "machine": machine_info(),
        "cases": args.cases,
        "seed": args.seed,
        "problems": problems,
        "statuses": {t: dict(c) for t, c in statuses.items()},
        "kinds": {t: dict(c) for t, c in kinds.items()},
    }
    (RESULTS / "fuzz_tools.json").write_text(json.dumps(result, indent=1, default=str))
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
