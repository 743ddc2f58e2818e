"""The tools under hostile command lines (test/support/tool_fuzz.py): a seeded, bounded
sample of cases, each run in this process; every failure is one line naming the problem
and leaves the folder as it was. bench/fuzz_tools.py runs thousands (docs/robustness.md)."""

import pytest

from ..support.tool_fuzz import Case, ToolFuzzer, check, prepare, run_case, snapshot

CASES = 60


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fuzz")
    prepare(folder)
    return folder


@pytest.mark.ros  # record's cases: rcl reads its ROS arguments first
@pytest.mark.parametrize("seed", [1, 2])
def test_hostile_command_lines_fail_in_one_line_and_leave_nothing(folder, seed):
    fuzzer = ToolFuzzer(seed)
    problems, statuses = [], []
    for _ in range(CASES // 2):
        case = fuzzer.case()
        before = snapshot(folder)
        status, out, err = run_case(case, folder)
        after = snapshot(folder)
        statuses.append(status)
        problem = check(case, status, out, err, before, after)
        if problem:
            problems.append(f"{case.tool} {case.argv}: {problem}")
        for name in set(after) - set(before):  # a success's outputs go, for the next case
            path = folder / name
            if path.is_file():
                path.unlink()
        for name in sorted(set(after) - set(before), reverse=True):
            if (folder / name).is_dir():
                (folder / name).rmdir()
    assert not problems, "\n".join(problems)
    assert set(statuses) <= {0, 1, 2} and statuses.count(0) < len(statuses)  # every case had a bad value


KNOWN_IDENTIFY = [
    Case("identify", ["rest.csv", "--out", "o.yaml", "--cutoff", "inf"]),
    Case("identify", ["absurd.csv", "--out", "o.yaml", "--quiet"]),
    Case("identify", ["field.csv", "--out", "o.yaml", "--quiet"]),
    Case("identify", ["rest.csv", "--out", "/proc/o.yaml", "--quiet"]),
    Case("identify", ["rest.csv", "--out", "o.yaml", "--plots", "afile/plots", "--quiet"]),
]
KNOWN_RECORD = [
    Case("record", ["record", "--out", "bag", "--depth", "-5"]),
    Case("record", ["record", "--out", "afile/bag"]),
    Case("record", ["record", "--out", "/proc/bag"]),
    Case("record", ["record", "--out", "bag", "--topic", "bad name"]),
]


def fail_in_one_line_and_write_nothing(cases, folder):
    for case in cases:
        before = snapshot(folder)
        status, out, err = run_case(case, folder)
        assert status in (1, 2), (case, out, err)
        assert check(case, status, out, err, before, snapshot(folder)) is None, (case, err)


@pytest.mark.ros  # rcl reads record's ROS arguments first
def test_known_hostile_record_command_lines(folder):
    """Examples found by the fuzz, each one line and nothing written."""
    fail_in_one_line_and_write_nothing(KNOWN_RECORD, folder)


def test_known_hostile_identify_command_lines(folder, capsys):
    """Examples found by the fuzz, each one line and nothing written, and what the line says."""
    fail_in_one_line_and_write_nothing(KNOWN_IDENTIFY, folder)
    status, _, err = run_case(Case("identify", ["rest.csv", "--out", "/proc/o.yaml"]), folder)
    assert err.strip() == "identify: error: /proc/o.yaml: cannot write in /proc (No such file or directory)"
    status, _, err = run_case(Case("identify", ["absurd.csv", "--out", "o.yaml", "--quiet"]), folder)
    assert "no sample has efforts" in err or "invalid" in err, err
    status, _, err = run_case(Case("identify", ["field.csv", "--out", "o.yaml", "--quiet"]), folder)
    assert len(err.strip().splitlines()) == 1 and err.startswith("identify: error: field.csv: "), err
