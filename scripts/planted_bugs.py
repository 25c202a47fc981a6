"""Planted-bug campaign: how many realistic mistakes does the test suite catch?

Each planted bug (the catalogue is ``planted_bugs.toml``) is a small,
realistic mistake in the Rust core (a dropped cosine, a density off by a
constant, a swapped argument, an off-by-one), with the tests that should
catch it. For every bug the campaign

1. applies it to a scratch worktree of HEAD (``git worktree add --detach``,
   made once and reset between bugs);
2. runs the bug's Rust tests, ``cargo test --lib -- FILTER...``, with
   ``CARGO_TARGET_DIR=/tmp/planted-target`` so that builds are incremental
   from bug to bug;
3. if they miss it (or always, with ``--keep-going``), builds the Python
   extension of the worktree into a dedicated virtualenv
   (``/tmp/planted-venv``, made once with ``--system-site-packages``) with
   ``maturin develop --release -q`` and runs the bug's pytest targets from
   the worktree's ``tests/`` directory.

A failing test catches the bug. A plant that does not compile, whose snippet
is not in the file exactly once, whose Rust filters select no test, or whose
pytest targets collect nothing is a defect of the campaign, not a catch: it
is reported as such and fails the run. The result is a table of every bug,
who caught it (``rust``, ``python``, ``MISSED``, ``compile-error``,
``snippet-missing``, ``campaign-error``), the first failing test and the time
taken. Command outputs are kept in ``/tmp/planted-logs``.

Run on demand (not in CI; a full campaign takes hours)::

    python scripts/planted_bugs.py                    # every bug
    python scripts/planted_bugs.py --only ID [ID ...] # some of them
    python scripts/planted_bugs.py --list             # the bugs and their tests
    python scripts/planted_bugs.py --check            # snippets and targets only, no build
    python scripts/planted_bugs.py --keep-going --report planted.md
    python scripts/planted_bugs.py --baseline         # first check that the tests pass on HEAD

A pytest target is a path under ``tests/`` (``test_render.py``), a node id
(``test_render.py::test_white_furnace``), optionally followed by ``-k EXPR``;
each target runs in its own ``pytest -q -x`` and the first failure stops the
bug's Python stage.

Exit status: 0 only if every bug is caught; 1 otherwise; 2 when the campaign
cannot go on (or ``--check`` finds a defect); 130 on Ctrl-C. An interrupted
or aborted campaign still reports the bugs it finished.
"""

from __future__ import annotations

import argparse
import datetime
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
VENV = Path("/tmp/planted-venv")
TARGET_DIR = Path("/tmp/planted-target")
LOG_DIR = Path("/tmp/planted-logs")
CATALOGUE = REPO / "scripts" / "planted_bugs.toml"
DEFAULT_TIMEOUT_MINUTES = 20.0

#: The fewest bugs each module must have (see ``--check``).
MINIMUM_PER_MODULE = {"render": 12, "envmap": 4, "phong": 3, "warp": 4, "distr": 4}


# --------------------------------------------------------------------------
# The bugs
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class Bug:
    """A planted bug: ``edits`` are (old, new) plain-string replacements in
    ``path`` (relative to the repository root), applied in order, each
    ``old`` required to occur exactly once when it is applied."""

    id: str
    description: str
    path: str
    edits: tuple[tuple[str, str], ...]
    cargo: tuple[str, ...] = ()
    pytest: tuple[str, ...] = ()

    @property
    def module(self) -> str:
        """``render`` for ``src/render/scene.rs``, ``phong`` for ``src/phong.rs``."""
        return Path(Path(self.path).parts[1]).stem


def load_bugs(path: Path) -> list[Bug]:
    """The catalogue: one ``[[bug]]`` table per bug, fields as in ``Bug``."""
    with path.open("rb") as f:
        tables = tomllib.load(f)["bug"]
    return [Bug(t["id"], t["description"], t["path"],
                tuple((old, new) for old, new in t["edits"]),
                tuple(t.get("cargo", ())), tuple(t.get("pytest", ()))) for t in tables]


BUGS: list[Bug] = load_bugs(CATALOGUE)


# --------------------------------------------------------------------------
# Planting
# --------------------------------------------------------------------------


class SnippetError(Exception):
    """An ``old`` snippet that does not occur exactly once."""


def apply_edits(text: str, bug: Bug) -> str:
    """``text`` with the bug's replacements made, each ``old`` checked to
    occur exactly once in the text it is applied to."""
    for k, (old, new) in enumerate(bug.edits, 1):
        count = text.count(old)
        if count != 1:
            first_line = old.strip().splitlines()[0]
            raise SnippetError(f"{bug.path}: edit {k} of {len(bug.edits)} occurs {count} times "
                               f"(expected exactly once): {first_line!r}")
        text = text.replace(old, new)
    return text


def plant_in(root: Path, bug: Bug) -> None:
    """Applies ``bug`` to its file under ``root``."""
    path = root / bug.path
    if not path.is_file():
        raise SnippetError(f"{bug.path}: no such file")
    path.write_text(apply_edits(path.read_text(), bug))


# --------------------------------------------------------------------------
# Running commands
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class Completed:
    returncode: int | None  # None: timed out
    output: str


def run(cmd: list[str], cwd: Path, env: dict[str, str] | None = None,
        timeout: float | None = None, log: Path | None = None) -> Completed:
    """Runs ``cmd`` in its own process group (killed whole on timeout or
    Ctrl-C), stdout and stderr together, the output also written to ``log``."""
    with subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, errors="replace",
                          start_new_session=True) as proc:
        try:
            output, _ = proc.communicate(timeout=timeout)
            returncode: int | None = proc.returncode
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            output, _ = proc.communicate()
            returncode = None
        except BaseException:
            os.killpg(proc.pid, signal.SIGKILL)
            raise
    if log is not None:
        log.parent.mkdir(parents=True, exist_ok=True)
        log.write_text(f"$ (cd {cwd} && {shlex.join(cmd)})\n{output}")
    return Completed(returncode, output)


def git(*args: str, cwd: Path = REPO, check: bool = True) -> str:
    done = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, check=False)
    if check and done.returncode != 0:
        raise CampaignAbort(f"git {' '.join(args)} failed:\n{done.stderr.strip()}")
    return done.stdout.strip()


class CampaignAbort(Exception):
    """The campaign cannot go on (no worktree, no venv, the wrong package)."""


# --------------------------------------------------------------------------
# Reading the tests' verdicts
# --------------------------------------------------------------------------

PASSED, CAUGHT, COMPILE_ERROR, ERROR = "passed", "caught", "compile error", "error"


@dataclass(frozen=True)
class Outcome:
    kind: str  # PASSED, CAUGHT, COMPILE_ERROR or ERROR
    detail: str = ""


CARGO_FAILED_TEST = re.compile(r"^test (\S+) \.\.\. FAILED", re.MULTILINE)
CARGO_RESULT = re.compile(r"^test result: \w+\. (\d+) passed; (\d+) failed", re.MULTILINE)
RUST_ERROR = re.compile(r"^error(?:\[E\d+\])?: .*$", re.MULTILINE)
PYTEST_FAILED = re.compile(r"^(?:FAILED|ERROR) (.+?)(?: - .*)?$", re.MULTILINE)
PYTEST_COUNT = re.compile(r"(\d+) (passed|failed|skipped|errors?|deselected|xfailed|xpassed)")


def tail(output: str, lines: int = 3) -> str:
    return " | ".join(line.strip() for line in output.strip().splitlines()[-lines:])


def build_failure(output: str) -> Outcome | None:
    """A compile error (with its first message) if cargo could not compile."""
    if "could not compile" not in output:
        return None
    first = RUST_ERROR.search(output)
    return Outcome(COMPILE_ERROR, first.group(0) if first else tail(output))


def cargo_verdict(done: Completed, what: str) -> Outcome:
    if done.returncode is None:
        return Outcome(ERROR, f"{what} timed out")
    failed = CARGO_FAILED_TEST.search(done.output)
    if failed:
        return Outcome(CAUGHT, failed.group(1))
    if (broken := build_failure(done.output)) is not None:
        return broken
    if done.returncode != 0:
        if "process didn't exit successfully" in done.output:
            return Outcome(CAUGHT, "the test binary crashed")
        return Outcome(ERROR, f"{what} exited with {done.returncode}: {tail(done.output)}")
    ran = sum(int(p) + int(f) for p, f in CARGO_RESULT.findall(done.output))
    if ran == 0:
        return Outcome(ERROR, "the cargo filters select no test")
    return Outcome(PASSED, f"{ran} Rust tests passed")


def pytest_counts(output: str) -> Counter[str]:
    """The counts of pytest's final summary line ("3 passed, 1 skipped in 2.0s")."""
    lines = [line for line in output.strip().splitlines() if re.search(r" in [\d.]+s", line)]
    counts: Counter[str] = Counter()
    for n, kind in PYTEST_COUNT.findall(lines[-1] if lines else ""):
        counts[kind] += int(n)
    return counts


def pytest_verdict(done: Completed, target: str) -> Outcome:
    code = done.returncode
    if code is None:
        return Outcome(ERROR, f"pytest {target} timed out")
    if code == 0:
        if pytest_counts(done.output)["passed"] == 0:
            return Outcome(ERROR, f"pytest {target}: every selected test was skipped")
        return Outcome(PASSED)
    if code == 5:
        return Outcome(ERROR, f"pytest {target}: no tests collected")
    if code == 4:
        return Outcome(ERROR, f"pytest {target}: usage error: {tail(done.output, 2)}")
    if code < 0:
        return Outcome(CAUGHT, f"{target}: pytest killed by signal {-code}")
    failed = PYTEST_FAILED.search(done.output)
    return Outcome(CAUGHT, failed.group(1) if failed else f"{target}: pytest exit {code}")


# --------------------------------------------------------------------------
# The stages
# --------------------------------------------------------------------------


@dataclass
class Stages:
    """Runs the Rust and Python tests of the scratch worktree."""

    worktree: Path
    timeout: float  # seconds, per command
    import_checked: bool = field(default=False, init=False)

    def env(self) -> dict[str, str]:
        env = dict(os.environ, CARGO_TARGET_DIR=str(TARGET_DIR), CARGO_TERM_COLOR="never",
                   VIRTUAL_ENV=str(VENV), PATH=f"{VENV / 'bin'}{os.pathsep}{os.environ['PATH']}")
        for name in ("PYTHONPATH", "PYTHONHOME", "CONDA_PREFIX"):
            env.pop(name, None)
        return env

    def rust(self, filters: tuple[str, ...], log_name: str) -> Outcome:
        done = run(["cargo", "test", "--lib", "--", *filters], self.worktree, self.env(),
                   self.timeout, LOG_DIR / f"{log_name}.cargo.log")
        return cargo_verdict(done, "cargo test")

    def python(self, targets: tuple[str, ...], log_name: str) -> Outcome:
        built = self.build(log_name)
        if built.kind != PASSED:
            return built
        self.check_import()
        for k, target in enumerate(targets):
            done = run([str(VENV / "bin" / "python"), "-m", "pytest", "-q", "-x",
                        "-p", "no:cacheprovider", *shlex.split(target)],
                       self.worktree / "tests", self.env(), self.timeout,
                       LOG_DIR / f"{log_name}.pytest{k}.log")
            verdict = pytest_verdict(done, target)
            if verdict.kind != PASSED:
                return verdict
        return Outcome(PASSED, f"{len(targets)} pytest targets passed")

    def build(self, log_name: str) -> Outcome:
        """``maturin develop`` of the worktree into the campaign's venv."""
        self.ensure_venv()
        env = self.env()
        maturin = shutil.which("maturin", path=env["PATH"])
        if maturin is None:
            raise CampaignAbort("maturin is not on PATH (pip install maturin)")
        done = run([maturin, "develop", "--release", "-q"], self.worktree, env, self.timeout,
                   LOG_DIR / f"{log_name}.maturin.log")
        if done.returncode is None:
            return Outcome(ERROR, "maturin develop timed out")
        if done.returncode != 0:
            return build_failure(done.output) or Outcome(
                ERROR, f"maturin develop exited with {done.returncode}: {tail(done.output)}")
        return Outcome(PASSED)

    @staticmethod
    def ensure_venv() -> None:
        if (VENV / "bin" / "python").exists():
            return
        print(f"creating {VENV} (--system-site-packages)", flush=True)
        done = run([sys.executable, "-m", "venv", "--system-site-packages", str(VENV)], REPO)
        if done.returncode != 0:
            raise CampaignAbort(f"could not create {VENV}: {tail(done.output)}")

    def check_import(self) -> None:
        """Once: pytest must import the worktree's package (installed in
        editable mode by maturin develop), not another copy."""
        if self.import_checked:
            return
        code = "import mcsample, mcsample._core as c; print(mcsample.__file__); print(c.__file__)"
        done = run([str(VENV / "bin" / "python"), "-c", code], self.worktree / "tests",
                   self.env())
        files = done.output.strip().splitlines()[-2:]
        root = self.worktree.resolve()
        if (done.returncode != 0 or len(files) != 2
                or not all(Path(f).resolve().is_relative_to(root) for f in files)):
            raise CampaignAbort(
                f"{VENV / 'bin' / 'python'} does not import mcsample from the worktree {root}:\n"
                f"{done.output.strip()}\n(check PYTHONPATH and the packages of {VENV})")
        self.import_checked = True


# --------------------------------------------------------------------------
# The campaign
# --------------------------------------------------------------------------

RUST, PYTHON, MISSED = "rust", "python", "MISSED"
DOES_NOT_COMPILE, SNIPPET_MISSING, CAMPAIGN_ERROR = (
    "compile-error", "snippet-missing", "campaign-error")
#: What a plant that fails in one of these ways is: a defect of the campaign.
DEFECTS = (DOES_NOT_COMPILE, SNIPPET_MISSING, CAMPAIGN_ERROR)


@dataclass(frozen=True)
class Result:
    bug: Bug
    caught_by: str  # "rust", "python", "rust+python", or one of the failures
    detail: str
    seconds: float

    @property
    def caught(self) -> bool:
        return self.caught_by != MISSED and self.caught_by not in DEFECTS


@contextmanager
def scratch_worktree() -> Iterator[Path]:
    """A detached worktree of HEAD in a fresh temporary directory, removed
    at the end."""
    tmp = Path(tempfile.mkdtemp(prefix="planted-"))
    worktree = tmp / "planted"
    git("worktree", "add", "--detach", str(worktree), "HEAD")
    try:
        yield worktree
    finally:
        try:
            git("worktree", "remove", "--force", str(worktree))
        except CampaignAbort as e:
            print(f"warning: {e}\n(remove it by hand: git worktree remove --force {worktree})",
                  file=sys.stderr)
        shutil.rmtree(tmp, ignore_errors=True)


def reset(worktree: Path) -> None:
    """Undoes every change to the tracked files (the built extension, ignored
    by git, stays)."""
    git("reset", "-q", "--hard", "HEAD", cwd=worktree)


def run_bug(bug: Bug, stages: Stages, keep_going: bool) -> Result:
    start = time.monotonic()

    def result(caught_by: str, detail: str) -> Result:
        return Result(bug, caught_by, detail, time.monotonic() - start)

    reset(stages.worktree)
    try:
        plant_in(stages.worktree, bug)
    except SnippetError as e:
        return result(SNIPPET_MISSING, str(e))
    try:
        catchers: list[str] = []
        details: list[str] = []
        stage_runs = [(RUST, bug.cargo, stages.rust), (PYTHON, bug.pytest, stages.python)]
        for name, tests, run_stage in stage_runs:
            if not tests or (catchers and not keep_going):
                continue
            outcome = run_stage(tests, bug.id)
            if outcome.kind == COMPILE_ERROR:
                return result(DOES_NOT_COMPILE, f"{name}: {outcome.detail}")
            if outcome.kind == ERROR:
                return result(CAMPAIGN_ERROR, f"{name}: {outcome.detail}")
            if outcome.kind == CAUGHT:
                catchers.append(name)
                details.append(outcome.detail)
        return result("+".join(catchers) or MISSED, "; ".join(details))
    finally:
        reset(stages.worktree)


def baseline(bugs: list[Bug], stages: Stages) -> None:
    """The campaign's tests on HEAD itself: they must all pass, or every
    bug they are meant to catch would count as caught."""
    reset(stages.worktree)
    filters = tuple(dict.fromkeys(f for bug in bugs for f in bug.cargo))
    targets = tuple(dict.fromkeys(t for bug in bugs for t in bug.pytest))
    print(f"baseline: {len(filters)} cargo filters, {len(targets)} pytest targets on HEAD",
          flush=True)
    for name, tests, run_stage in ((RUST, filters, stages.rust), (PYTHON, targets, stages.python)):
        outcome = run_stage(tests, "baseline") if tests else Outcome(PASSED)
        if outcome.kind != PASSED:
            raise CampaignAbort(f"the baseline (HEAD, no bug) does not pass: {name}: "
                                f"{outcome.kind}: {outcome.detail}")


def announce(index: int, total: int, result: Result) -> None:
    line = (f"[{index}/{total}] {result.bug.id}: {result.caught_by}"
            f" ({format_seconds(result.seconds)}) {result.detail}")
    if result.caught_by in DEFECTS:
        banner = "!" * 78
        line = (f"{banner}\n{line}\n!!! {result.caught_by}: a defect of the campaign, not a "
                f"catch; fix the plant (logs in {LOG_DIR})\n{banner}")
    print(line, flush=True)


def campaign(bugs: list[Bug], args: argparse.Namespace) -> int:
    commit = git("rev-parse", "--short", "HEAD")
    print(f"planted-bug campaign: {len(bugs)} bugs at {commit}; target dir {TARGET_DIR}, "
          f"venv {VENV}, logs {LOG_DIR}", flush=True)
    results: list[Result] = []
    status = None
    try:
        with scratch_worktree() as worktree:
            stages = Stages(worktree, args.timeout * 60)
            if args.baseline:
                baseline(bugs, stages)
            for index, bug in enumerate(bugs, 1):
                results.append(run_bug(bug, stages, args.keep_going))
                announce(index, len(bugs), results[-1])
    except CampaignAbort as e:
        print(f"\ncampaign aborted: {e}", file=sys.stderr)
        status = 2
    except KeyboardInterrupt:
        print("\ninterrupted", file=sys.stderr)
        status = 130
    if results:
        report(results, commit, args.report)
    if status is not None:
        return status
    return 0 if all(r.caught for r in results) else 1


# --------------------------------------------------------------------------
# Reports
# --------------------------------------------------------------------------

COLUMNS = ("id", "description", "caught by", "first failing test / detail", "time")


def format_seconds(seconds: float) -> str:
    minutes, secs = divmod(round(seconds), 60)
    return f"{minutes}m{secs:02d}s" if minutes else f"{secs}s"


def rows(results: list[Result]) -> list[tuple[str, ...]]:
    return [(r.bug.id, r.bug.description, r.caught_by, r.detail, format_seconds(r.seconds))
            for r in results]


def summary(results: list[Result]) -> str:
    counts = Counter("caught" if r.caught else r.caught_by for r in results)
    parts = [f"{counts.pop('caught', 0)}/{len(results)} caught"]
    parts += [f"{n} {kind}" for kind, n in sorted(counts.items())]
    return ", ".join(parts)


def text_table(table: list[tuple[str, ...]]) -> str:
    widths = [max(len(row[k]) for row in [COLUMNS, *table]) for k in range(len(COLUMNS))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip()
             for row in [COLUMNS, *table]]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def markdown_table(table: list[tuple[str, ...]]) -> str:
    def line(cells: tuple[str, ...]) -> str:
        return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"
    return "\n".join([line(COLUMNS), line(tuple("---" for _ in COLUMNS)), *map(line, table)])


def report(results: list[Result], commit: str, path: Path | None) -> None:
    table = rows(results)
    print(f"\n{text_table(table)}\n\n{summary(results)}")
    if path is None:
        return
    when = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    path.write_text(f"# Planted-bug campaign at {commit} ({when})\n\n{markdown_table(table)}\n\n"
                    f"{summary(results)}\n")
    print(f"report written to {path}")


# --------------------------------------------------------------------------
# --list and --check
# --------------------------------------------------------------------------


def print_list(bugs: list[Bug]) -> None:
    for bug in bugs:
        print(f"{bug.id}  [{bug.module}, {bug.path}]\n    {bug.description}\n"
              f"    cargo: {' '.join(bug.cargo) or '-'}\n"
              f"    pytest: {'; '.join(bug.pytest) or '-'}")
    print(f"\n{len(bugs)} bugs: " + ", ".join(
        f"{module} {n}" for module, n in Counter(b.module for b in bugs).items()))


def rust_test_paths(repo: Path) -> list[str]:
    """Approximate paths of the crate's unit tests (``module::fn`` and
    ``module::tests::fn``), for checking the cargo filters without a build."""
    paths = []
    for file in sorted((repo / "src").rglob("*.rs")):
        parts = list(file.relative_to(repo / "src").with_suffix("").parts)
        if parts[-1] in ("mod", "lib"):
            parts.pop()
        module = "::".join(parts)
        for name in re.findall(r"#\[test\]\s*(?:#\[[^\]]*\]\s*)*fn\s+(\w+)", file.read_text()):
            paths += [f"{module}::{name}", f"{module}::tests::{name}"]
    return paths


def target_problem(target: str, tests_dir: Path) -> str | None:
    """What is wrong with a pytest target that can be seen without running it."""
    try:
        words = shlex.split(target)
    except ValueError as e:
        return f"{target!r}: {e}"
    file, *nodes = words[0].split("::")
    if not (tests_dir / file).is_file():
        return f"{target!r}: no file tests/{file}"
    source = (tests_dir / file).read_text()
    for node in nodes:
        name = node.split("[")[0]
        if not re.search(rf"^\s*def {re.escape(name)}\(", source, re.MULTILINE):
            return f"{target!r}: no test {name} in tests/{file}"
    extra = words[1:]
    if extra and (len(extra) != 2 or extra[0] != "-k"):
        return f"{target!r}: only '-k EXPR' may follow the path"
    return None


def bug_problems(bug: Bug, tests: list[str]) -> list[str]:
    problems = []
    try:
        path = REPO / bug.path
        if not path.is_file():
            raise SnippetError(f"{bug.path}: no such file")
        if apply_edits(path.read_text(), bug) == path.read_text():
            problems.append("the edits change nothing")
    except SnippetError as e:
        problems.append(str(e))
    if not re.fullmatch(r"[a-z0-9]+(-[a-z0-9]+)*", bug.id):
        problems.append("the id is not kebab-case")
    if not bug.cargo and not bug.pytest:
        problems.append("no test is meant to catch it")
    problems += [f"cargo filter {f!r} selects no test" for f in bug.cargo
                 if not any(f in t for t in tests)]
    problems += [p for t in bug.pytest if (p := target_problem(t, REPO / "tests"))]
    return problems


def list_problems() -> list[str]:
    """Problems of the list as a whole: repeated ids, too few bugs in a module."""
    problems = [f"id {i!r} is used {n} times" for i, n in Counter(b.id for b in BUGS).items()
                if n > 1]
    per_module = Counter(b.module for b in BUGS)
    problems += [f"module {m} has {per_module[m]} bugs, fewer than {n}"
                 for m, n in MINIMUM_PER_MODULE.items() if per_module[m] < n]
    return problems


def check(bugs: list[Bug]) -> int:
    """Verifies every bug against the working tree, without building."""
    tests = rust_test_paths(REPO)
    failed = 0
    for bug in bugs:
        problems = bug_problems(bug, tests)
        failed += bool(problems)
        edits = f"{len(bug.edits)} edit{'s' if len(bug.edits) > 1 else ''}"
        print(f"{'FAIL' if problems else 'ok  '}  {bug.id}  ({bug.path}, {edits})")
        for problem in problems:
            print(f"        {problem}")
    overall = list_problems()
    for problem in overall:
        print(f"FAIL  {problem}")
    modules = ", ".join(f"{m} {n}" for m, n in Counter(b.module for b in bugs).items())
    print(f"\n{len(bugs) - failed}/{len(bugs)} bugs ok ({modules})")
    return 2 if failed or overall else 0


# --------------------------------------------------------------------------
# Command line
# --------------------------------------------------------------------------


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--only", nargs="+", action="extend", metavar="ID",
                        help="run only these bugs")
    parser.add_argument("--list", action="store_true", help="list the bugs and their tests")
    parser.add_argument("--check", action="store_true",
                        help="only verify the snippets and test targets against the working "
                             "tree (no build)")
    parser.add_argument("--keep-going", action="store_true",
                        help="run the Python tests even when the Rust tests caught the bug")
    parser.add_argument("--baseline", action="store_true",
                        help="first run every selected test on HEAD: they must pass")
    parser.add_argument("--report", type=Path, help="also write the table as markdown here")
    parser.add_argument("--timeout", type=float, default=DEFAULT_TIMEOUT_MINUTES,
                        metavar="MINUTES", help="per command (default %(default)g)")
    return parser.parse_args(argv)


def select(only: list[str] | None) -> list[Bug]:
    """The bugs named by ``--only`` (all without it), in the list's order."""
    if not only:
        return BUGS
    unknown = sorted(set(only) - {bug.id for bug in BUGS})
    if unknown:
        raise ValueError(f"unknown bug ids: {', '.join(unknown)} (see --list)")
    return [bug for bug in BUGS if bug.id in only]


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    try:
        bugs = select(args.only)
    except ValueError as e:
        print(e, file=sys.stderr)
        return 2
    if args.list:
        print_list(bugs)
        return 0
    if args.check:
        return check(bugs)
    return campaign(bugs, args)


if __name__ == "__main__":
    sys.exit(main())
