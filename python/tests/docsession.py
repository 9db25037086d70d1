# SPDX-License-Identifier: Apache-2.0
"""A page of the manual worked through as a reader would: its commands and programs in
order, in a folder of their own, on the software bus the page starts.

:class:`Session` runs a page's ``sh``, ``console`` and ``python`` blocks (docblocks.py)
one after the other; what one starts in the background (``&``) runs until the page ends.
Every line of an ``sh`` or ``console`` block is either run or checked, by its program
(``RULES``); a line no rule knows fails the test, so no page shows a command nothing
looks at.

Run (the session's folder holds links to the repository's ``examples/``, ``python/``,
``bench/`` and ``configs/``, so the paths the pages name work):

- ``canola ...``: the command, from this Python environment. Commands that run until
  stopped (``canola bus serve``, ``canola bus bridge``, ``canola device``, ``canola
  gateway``, ``canola view``, a ``canola dump`` of the bus without a bound) are stopped
  by SIGINT, or SIGTERM at the page's end, once they printed what the page shows (else
  ``READY``); every other one (``canola monitor`` too: its output is no terminal) must
  end by itself with exit code 0 and nothing on stderr.
- ``build/canola-node ...``: the C device (``make`` builds it; the page is skipped
  without it).
- ``python FILE ...``: the program, with this Python.
- ``ls ...``, ``mkdir ...``: to show what a command left behind, to make a folder (in
  the session's folder).
- ``export NAME=VALUE``: for every command after it.

Checked, not run (they build or install for minutes, or fuzz for hours; what runs them
for real is named):

- ``make TARGET... [VAR=VALUE]``: ``make -n TARGET`` succeeds (the target exists) and each
  VAR is the Makefile's. ``.ci/run`` runs ``make test``, ``make demo``, ``make bench``...
- ``cmake ...``: each ``-DNAME`` is a variable of CMakeLists.txt or cmake/ (or CMake's
  own ``CMAKE_*``), each file it names exists, ``--build``/``--install`` name a folder an
  earlier ``-B`` made (``tests/packaging/c-install`` configures, builds and installs).
- ``cc ...``: each ``pkg-config`` package it names is one the install writes
  (cmake/CanolaPackage.cmake).
- ``pip install ...`` and ``python -m build ... python``: the package folder is python/
  and ``build`` is pinned in its test extra (``test_packaging.py`` builds and installs).
- ``build-fuzz/fuzz_TARGET ...``, ``python fuzz/*.py ...``: the target is one the Makefile
  builds (``FUZZ_TARGETS``), the script exists, and so does every corpus or dictionary
  named (``make fuzz`` runs them).

What the session makes its own, so that a page's commands run anywhere, side by side:

- every socketcand URL (``socketcand://HOST:PORT/CHANNEL``, in arguments, in ``export``
  and in python blocks' text) reaches the page's hub at the port it really got, and so
  does ``--iface IFACE`` (as ``--bus socketcand://...:PORT/IFACE``): a hub the page
  starts (``canola bus serve &``), else one the session starts for the page;
- the hub listens on port 0 (``--port`` and ``--host`` replaced), the gateway on
  ``tcp:127.0.0.1:0`` (a Unix socket in the session's folder), ``canola view`` on
  ``127.0.0.1:0``, ``--store`` folders are
  in the session's folder;
- commands that wait for a device get a time-out a starved machine meets
  (:func:`starved_timeouts`; they end when the answer comes);
- ``firmware.bin`` and ``app.bin``, the images a reader brings, are random bytes;
- in output, the ports really used read as the ones the page shows.

A python block runs as a program in the session's folder (``docshim.py``): a python-can
bus it opens on a real interface (``can.Bus(interface="socketcan", channel="can0")``)
is python-can's virtual bus of that channel instead, in the block's own process.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from docblocks import ROOT, Block, Step, shows
from leftovers import end_process

from canola.cli import build_parser
from canola.cli.common import UsageError
from canola.formats import odgen

NODE_BIN = Path(os.environ.get("CANOLA_NODE_BIN", ROOT / "build" / "canola-node"))
SHIM = Path(__file__).resolve().parent / "docshim.py"

#: Bounds, not expected times: a starved machine starts a Python process in seconds.
COMMAND_S = 300.0
READY_S = 120.0

#: The repository's folders a session's folder links to.
LINKED = ("examples", "python", "bench", "configs", "fuzz")
#: The files a reader brings: (name, size), random bytes.
BROUGHT = (("firmware.bin", 3000), ("app.bin", 2000))

#: What a command that runs until stopped prints once it is ready, by the command's start
#: (used when the page shows no output for it).
READY = {
    "canola bus serve": r"socketcand hub on 127\.0\.0\.1:\d+",
    "canola bus bridge": r"canola bus: .* joined to ",
    "canola device": r"canola device: node \d+ from .* running",
    "canola gateway": r"listening on ",
    "canola view": r"canola view: http://",
    "build/canola-node": r"canola-node: node \d+ on ",
}
_ALWAYS_RUNNING = ("canola bus serve", "canola bus bridge", "canola device", "canola gateway",
                   "canola view", "build/canola-node")

#: Environment a reader's shell may have that names a default bus: not the session's.
_BUS_ENV = ("CANOLA_BUS", "CAN_INTERFACE", "CAN_CHANNEL", "CAN_CONFIG", "CAN_BITRATE")
_URL = re.compile(r"socketcand://[^/\s\"']+/")


class Proc:
    """A command run in the background, its output (stdout and stderr) collected."""

    def __init__(self, argv: list[str], cwd: Path, env: dict[str, str]) -> None:
        self.popen = subprocess.Popen(argv, cwd=cwd, env=env, stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                      text=True)
        self.out: list[str] = []
        self._reader = threading.Thread(target=lambda: self.out.extend(self.popen.stdout
                                                                       or ()), daemon=True)
        self._reader.start()

    def text(self) -> str:
        return "".join(self.out)

    def wait_until(self, done: Callable[[str], bool], what: str,
                   timeout: float = READY_S) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if done(self.text()):
                return
            if self.popen.poll() is not None and not self._reader.is_alive():
                break
            time.sleep(0.05)
        raise AssertionError(f"{what}; it printed: {self.text()!r}")

    def stop(self, sig: int = signal.SIGTERM) -> int:
        code, _ = end_process(self.popen, sig)  # a hung one's stacks in its output
        self._reader.join(10)
        return code


def _accepts(words: list[str], option: str) -> bool:
    """Whether ``canola WORDS...`` takes ``option`` (asked of the CLI's own parser)."""
    _, unknown = build_parser().parse_known_args([*words[1:], option, "1"])
    return option not in unknown


def starved_timeouts(words: list[str]) -> list[str]:
    """Time-outs a starved machine meets, for the commands that wait for a device: it is
    another process behind the hub and answers later than the defaults (a run at load 28
    got no answer to `canola lss set-id` in LSS's 100 ms, nor to `canola pdo map` in the
    SDO's 1000 ms). Bounds, not waits: each command ends when its answer came. None where
    the page sets one itself."""
    if words[1] == "lss":  # a fastscan waits this long for each probe nobody answers
        return [] if "--timeout" in words else ["--timeout", "3000"]
    if words[1] in ("sdo", "scan"):
        return [] if "--timeout" in words else ["--timeout", "10000"]
    if "--sdo-timeout" not in words and _accepts(words, "--sdo-timeout"):
        return ["--sdo-timeout", "10000"]
    return []


def _runs_until_stopped(words: list[str]) -> bool:
    line = " ".join(words)
    if line.startswith(_ALWAYS_RUNNING):
        return not (words[:2] == ["canola", "gateway"] and "stdio" in words)
    if words[:2] == ["canola", "dump"]:
        positional = [w for w in words[2:] if not w.startswith("-")]
        return not {"--count", "--duration"} & set(words) and not positional
    return False


def _ready_pattern(words: list[str]) -> str:
    line = " ".join(words)
    for start in sorted(READY, key=len, reverse=True):
        if line.startswith(start):
            return READY[start]
    raise AssertionError(f"{line}: runs until stopped, but neither the page shows what it "
                         "prints nor does READY know")


class Session:
    """One page's blocks, run in ``folder`` (see the module's text)."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.env = {k: v for k, v in os.environ.items() if k not in _BUS_ENV}
        self.env["PYTHONFAULTHANDLER"] = "1"  # a hung command, stopped, says where
        self.background: list[Proc] = []
        self.hub: Proc | None = None
        self.hub_port: str | None = None
        self.shown_ports: dict[str, str] = {}  # a port really used -> the page's
        self.shown_listen: str | None = None  # where the page's gateway listens
        self.shown_view: str | None = None  # where the page's canola view serves
        self.build_dirs: set[str] = set()
        self.transcript: list[tuple[str, str]] = []  # (command, what it printed)
        for name in LINKED:
            (folder / name).symlink_to(ROOT / name)
        for name, size in BROUGHT:
            (folder / name).write_bytes(os.urandom(size))

    # ---- the page's blocks

    def run(self, block: Block) -> None:
        if block.not_run is not None:
            self.check(block)
            return
        if block.lang == "python":
            self.run_python(block)
        for step in block.steps:
            try:
                self.run_step(step)
            except AssertionError as exc:
                raise AssertionError(f"{block.where} (line {step.line}: {step.command}): "
                                     f"{exc}") from None

    def check(self, block: Block) -> None:
        """A block the page marks ``<!-- not run: WHY -->``: a python block must compile;
        each ``canola`` line must be one the CLI's parser takes (the command, every option
        and every value's form); every other line must be one of the rules that only check
        (make, cmake, cc, pip, the fuzzers)."""
        if block.lang == "python":
            compile(block.text, block.where, "exec")
        for step in block.steps:
            words = [w for w in step.words() if w != "&"]
            while re.fullmatch(r"[A-Z_][A-Z0-9_]*=.*", words[0]) and len(words) > 1:
                words.pop(0)
            where = f"{block.where} (line {step.line}: {step.command})"
            if words[0] == "canola":
                assert _parses(words), f"{where}: the canola CLI refuses it"
            else:
                rule = RULES.get(words[0])
                assert rule in _CHECK_ONLY, f"{where}: a not-run block that nothing checks"
                rule(self, words, step, {})

    def run_step(self, step: Step) -> None:
        words = step.words()
        assert words, "an empty command"
        env: dict[str, str] = {}
        while re.fullmatch(r"[A-Z_][A-Z0-9_]*=.*", words[0]) and len(words) > 1:
            name, _, value = words.pop(0).partition("=")
            env[name] = value
        rule = RULES.get(words[0])
        if rule is None and words[0].startswith("build-fuzz/"):
            rule = _fuzzer
        assert rule is not None, (f"no rule runs or checks '{words[0]}' (docsession.RULES): "
                                  "show it in prose, or give it a rule")
        rule(self, words, step, env)

    def run_python(self, block: Block) -> None:
        source = block.text
        if self.hub_port is not None:
            source = _URL.sub(self._url_here, source)
            source = re.sub(r"\bport=29536\b", f"port={self.hub_port}", source)
        script = self.folder / f"block_{block.line}.py"
        script.write_text(source, encoding="utf-8")
        done = subprocess.run([sys.executable, str(SHIM), script.name], cwd=self.folder,
                              env=self._env({}), capture_output=True, text=True,
                              timeout=COMMAND_S, check=False)
        self.transcript.append((f"python block {block.where}", self._as_shown(done.stdout)))
        assert done.returncode == 0, f"{block.where}: exit {done.returncode}: {done.stderr}"
        if block.output is not None:
            missing = shows(block.output, self._as_shown(done.stdout))
            assert missing is None, (f"{block.where}: the page shows {missing!r}; the "
                                     f"program printed:\n{done.stdout}")

    def close(self) -> None:
        for proc in reversed(self.background):
            proc.stop()
        self.background.clear()

    # ---- what the session makes its own

    def _url_here(self, m: re.Match[str]) -> str:
        return f"socketcand://127.0.0.1:{self._hub_port()}/"

    def _hub_port(self) -> str:
        if self.hub_port is None:  # the page starts none: one for it
            self._start_hub(["canola", "bus", "serve"], None)
        assert self.hub_port is not None
        return self.hub_port

    def _mapped(self, text: str) -> str:
        return _URL.sub(self._url_here, text) if "socketcand://" in text else text

    def _env(self, extra: dict[str, str]) -> dict[str, str]:
        env = {**self.env, **extra}
        return {k: self._mapped(v) for k, v in env.items()}

    def _as_shown(self, text: str) -> str:
        for real, page in self.shown_ports.items():
            text = re.sub(rf"(?<=:){real}\b", page, text)
        if self.shown_listen is not None:
            text = re.sub(r"(?<=listening on )\S+", self.shown_listen, text)
        if self.shown_view is not None:
            text = re.sub(r"(?<=canola view: http://)[^/\s]+", self.shown_view, text)
        return text

    def _bus_words(self, words: list[str]) -> list[str]:
        out: list[str] = []
        it = iter(words)
        for word in it:
            if word == "--iface":
                out += ["--bus", f"socketcand://127.0.0.1:{self._hub_port()}/{next(it)}"]
            else:
                out.append(self._mapped(word))
        return out

    def _start_hub(self, words: list[str], step: Step | None) -> None:
        assert self.hub is None, "a second hub on one page"
        shown_port = _option(words, "--port") or "29536"
        words = _without(_without(words, "--port"), "--host")
        argv = [sys.executable, "-m", "canola.cli", *words[1:], "--port", "0"]
        # the hub's environment as it is: the URLs in it are its clients'
        proc = self._background(argv, {**self.env}, step, words)
        m = re.search(READY["canola bus serve"], proc.text())
        assert m is not None
        self.hub = proc
        self.hub_port = m.group(0).rsplit(":", 1)[1]
        self.shown_ports[self.hub_port] = shown_port

    # ---- running

    def _background(self, argv: list[str], env: dict[str, str], step: Step | None,
                    words: list[str]) -> Proc:
        """Start ``argv`` (environment ``env`` as it is) and wait until it is ready."""
        proc = Proc(argv, self.folder, env)
        self.background.append(proc)
        if step is not None and step.shown:
            shown = step.shown
            proc.wait_until(lambda text: shows(shown, self._as_shown(text)) is None,
                            f"the page shows {shown!r}")
        else:
            pattern = _ready_pattern(words)
            proc.wait_until(lambda text: re.search(pattern, text, re.M) is not None,
                            f"not ready: no {pattern!r}")
        return proc

    def run_program(self, argv: list[str], words: list[str], step: Step,
                    env: dict[str, str]) -> None:
        """Run a program of the page: in the background (``&``), until ready then
        interrupted (a command that runs until stopped), or to its end."""
        if words[-1] == "&":
            proc = self._background(argv, self._env(env), step, words[:-1])
            self.transcript.append((step.command, self._as_shown(proc.text())))
            return
        if _runs_until_stopped(words):
            proc = self._background(argv, self._env(env), step, words)
            self.background.remove(proc)
            code = proc.stop(signal.SIGINT)
            self.transcript.append((step.command, self._as_shown(proc.text())))
            assert code == 0, f"exit {code} after Ctrl-C: {proc.text()}"
            return
        done = subprocess.run(argv, cwd=self.folder, env=self._env(env),
                              stdin=subprocess.DEVNULL, capture_output=True, text=True,
                              timeout=COMMAND_S, check=False)
        self.transcript.append((step.command, self._as_shown(done.stdout + done.stderr)))
        assert (done.returncode, done.stderr) == (0, ""), (
            f"exit {done.returncode}; stdout {done.stdout!r}; stderr {done.stderr!r}")
        if step.shown:
            missing = shows(step.shown, self._as_shown(done.stdout))
            assert missing is None, (f"the page shows {missing!r}; it printed:\n"
                                     f"{done.stdout}")


def _parses(words: list[str]) -> bool:
    """Whether the CLI's own parser takes ``canola WORDS...`` (it prints why not)."""
    parser = odgen.build_parser("canola odgen") if words[1:2] == ["odgen"] else build_parser()
    try:
        parser.parse_args(words[2:] if words[1:2] == ["odgen"] else words[1:])
    except UsageError as exc:
        print(exc)
        return False
    except SystemExit as exc:
        return exc.code == 0
    return True


def _option(words: list[str], name: str) -> str | None:
    return words[words.index(name) + 1] if name in words[:-1] else None


def _without(words: list[str], name: str) -> list[str]:
    """``words`` without option ``name`` and its value."""
    if name not in words:
        return words
    i = words.index(name)
    return words[:i] + words[i + 2:]


# ---- the rules: run

Rule = Callable[[Session, list[str], Step, dict[str, str]], None]


def _export(session: Session, words: list[str], step: Step, env: dict[str, str]) -> None:
    for word in words[1:]:
        name, sep, value = word.partition("=")
        assert sep and re.fullmatch(r"[A-Z_][A-Z0-9_]*", name), f"export {word!r}"
        session.env[name] = value


def _canola(session: Session, words: list[str], step: Step, env: dict[str, str]) -> None:
    background = words[-1] == "&"
    line = [w for w in words if w != "&"]
    if line[:3] == ["canola", "bus", "serve"]:
        assert background, "the page's hub runs in the background (canola bus serve &)"
        session._start_hub(line, step)
        return
    if line[:2] == ["canola", "gateway"]:
        line = _gateway_listen(session, line)
    if line[:2] == ["canola", "view"]:  # its page on a free port
        session.shown_view = _option(line, "--listen") or "127.0.0.1:8080"
        line = [*_without(line, "--listen"), "--listen", "127.0.0.1:0"]
    if "--store" in line[:-1]:
        i = line.index("--store") + 1
        line[i] = str(session.folder / Path(line[i]).name)
    argv = [sys.executable, "-m", "canola.cli", *session._bus_words(line[1:]),
            *starved_timeouts(line)]
    session.run_program(argv, words, step, env)


def _gateway_listen(session: Session, words: list[str]) -> list[str]:
    where = _option(words, "--listen")
    if where == "stdio":
        return words
    session.shown_listen = where or "tcp:127.0.0.1:6000"
    words = _without(words, "--listen")
    if where is not None and where.startswith("unix:"):
        return [*words, "--listen", f"unix:{session.folder / Path(where[5:]).name}"]
    return [*words, "--listen", "tcp:127.0.0.1:0"]


def _canola_node(session: Session, words: list[str], step: Step,
                 env: dict[str, str]) -> None:
    if not NODE_BIN.exists():
        pytest.skip(f"no canola-node program at {NODE_BIN} (make builds it)")
    line = [w for w in words if w != "&"]
    if "--store" in line[:-1]:
        i = line.index("--store") + 1
        line[i] = str(session.folder / Path(line[i]).name)
    argv = [str(NODE_BIN), *session._bus_words(line[1:])]
    session.run_program(argv, words, step, env)


def _python(session: Session, words: list[str], step: Step, env: dict[str, str]) -> None:
    if words[1:3] == ["-m", "build"]:
        _check_python_build(words)
        return
    script = words[1]
    if script.startswith("fuzz/"):
        _check_fuzzer(words[1:])
        return
    assert (session.folder / script).is_file(), f"{script}: no such file"
    session.run_program([sys.executable, *words[1:]], words, step, env)


def _file_tool(session: Session, words: list[str], step: Step, env: dict[str, str]) -> None:
    session.run_program(words, words, step, env)


# ---- the rules: check

def _make(session: Session, words: list[str], step: Step, env: dict[str, str]) -> None:
    makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
    targets = []
    for word in [*words[1:], *(f"{k}={v}" for k, v in env.items())]:
        name, sep, _ = word.partition("=")
        if sep:
            assert re.search(rf"\b{name}\b", makefile), f"{name}: not a variable of the Makefile"
        else:
            targets.append(word)
    for target in targets or ["all"]:
        done = subprocess.run(["make", "-n", "--no-print-directory", target], cwd=ROOT,
                              capture_output=True, text=True, timeout=COMMAND_S, check=False,
                              env={**os.environ, "MAKEFLAGS": ""})
        assert done.returncode == 0, f"make -n {target}: {done.stderr.strip()}"


def _repo_file(word: str) -> None:
    """A word naming a file or folder of the repository: it exists."""
    assert (ROOT / word).exists(), f"{word}: no such file in the repository"


def _cmake(session: Session, words: list[str], step: Step, env: dict[str, str]) -> None:
    known = "\n".join(p.read_text(encoding="utf-8") for p in
                      [ROOT / "CMakeLists.txt", *sorted((ROOT / "cmake").glob("*"))])
    it = iter(words[1:])
    for word in it:
        if word in ("-S",):
            _repo_file(next(it))
        elif word == "-B":
            session.build_dirs.add(next(it))
        elif word in ("--build", "--install"):
            folder = next(it)
            assert folder in session.build_dirs, f"{word} {folder}: no -B {folder} before"
        elif word.startswith("-D"):
            name, _, value = word[2:].partition("=")
            name = name.split(":")[0]
            assert name.startswith("CMAKE_") or re.search(rf"\b{name}\b", known), (
                f"-D{name}: not a variable of CMakeLists.txt or cmake/")
            if value.endswith(".h"):
                _repo_file(value)


def _cc(session: Session, words: list[str], step: Step, env: dict[str, str]) -> None:
    package = (ROOT / "cmake" / "CanolaPackage.cmake").read_text(encoding="utf-8")
    written = set(re.findall(r"^\s*canola_pc\((\S+)", package, re.M))
    named = [w.rstrip(")") for w in words if w.startswith("canola")]
    assert named, "a cc line names the pkg-config package it builds with"
    for name in named:
        assert name in written, f"{name}: the install writes no {name}.pc ({sorted(written)})"


def _pip(session: Session, words: list[str], step: Step, env: dict[str, str]) -> None:
    assert words[1] == "install", "pip install ..."
    for word in words[2:]:
        if word.startswith("-"):
            continue
        if word.startswith("build-dist/"):
            assert re.fullmatch(r"build-dist/canola-\*\.whl", word), word
        else:
            folder = word.split("[")[0].strip("'\"")
            assert folder == "python", f"{word}: the Python package is python/"
    pyproject = (ROOT / "python" / "pyproject.toml").read_text(encoding="utf-8")
    assert re.search(r'^name = "canola"$', pyproject, re.M)


def _check_python_build(words: list[str]) -> None:
    assert words[-1] == "python", "python -m build ... python (the package's folder)"
    pyproject = (ROOT / "python" / "pyproject.toml").read_text(encoding="utf-8")
    assert re.search(r'^\s*"build==', pyproject, re.M), "build is pinned in the test extra"


def _check_fuzzer(words: list[str]) -> None:
    program = words[0]
    if program.startswith("build-fuzz/fuzz_"):
        makefile = (ROOT / "Makefile").read_text(encoding="utf-8")
        m = re.search(r"^FUZZ_TARGETS = (.*)$", makefile, re.M)
        assert m is not None
        target = program.removeprefix("build-fuzz/fuzz_")
        assert target in m.group(1).split(), f"{program}: not one of the Makefile's targets"
    else:
        _repo_file(program)
    for word in words[1:]:
        path = word.split("=", 1)[-1]
        if path.startswith("fuzz/"):
            _repo_file(path)


def _fuzzer(session: Session, words: list[str], step: Step, env: dict[str, str]) -> None:
    _check_fuzzer(words)


RULES: dict[str, Rule] = {
    "export": _export,
    "canola": _canola,
    "build/canola-node": _canola_node,
    "python": _python,
    "python3": _python,
    "build-py/venv/bin/python": _python,
    "ls": _file_tool,
    "mkdir": _file_tool,
    "make": _make,
    "cmake": _cmake,
    "cc": _cc,
    "pip": _pip,
}
#: The rules that check a line without running anything.
_CHECK_ONLY = {_make, _cmake, _cc, _pip, _fuzzer}
