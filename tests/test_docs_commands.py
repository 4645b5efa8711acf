"""Every documented command works.

Every ``exact-khk ...`` command line shown in a shell block (```bash, ```sh,
```shell, ```console) of README.md and docs/*.md, and every one in inline code
in their prose (`` `exact-khk orbit --steps 5` ``), is extracted and run in-process
through :func:`exact_khk.cli.main.main`, in a fresh temporary folder, and must
end with the exit status the text implies: 0, unless the line's own comment
says otherwise (``# exit 4``, ``# exits with status 1``, ``# -> exit 2``), or, for
inline code, the words right after it (`` `...` (exit 2)``, `` `...` exits 4``).
Where the text names the verdict a command prints (``# VALID``, ``# last line
VERIFIED: ...``, ``the verdict, e.g. `VALID: ...` ``), its output must contain it.

Extraction is deliberately tolerant of the docs being rewritten: shell prompts
(``$ ``), line continuations (``\\``), chains (``&&``, ``;``, ``|``: the
exact-khk segment is taken), ``python -m exact_khk``, environment assignments
(``VAR=value exact-khk ...``) and trailing comments are handled.  Nothing is
skipped silently: a command that cannot run here is listed in :data:`ALLOW`
with the reason (it is then reported as skipped), one that runs for long in
:data:`SLOW` (it runs under ``-m slow``), and a command with a placeholder
(``FILE``, ``NAME``, ``<path>``, ``...``) that is in neither makes the test
fail, naming the file and line.

Every ``python scripts/NAME.py ...`` command shown (in shell blocks or inline code) is
checked too: quickly in the default suite (the script starts and its ``--help`` lists
every option the command gives), and run as shown, in a copy of the repository, under
``-m slow`` (benchmarks and studies: minutes to tens of minutes each).
"""

from __future__ import annotations

import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys

import pytest

from exact_khk.cli.main import main

ROOT = pathlib.Path(__file__).resolve().parent.parent
SHELL_LANGS = {"bash", "sh", "shell", "console", "zsh"}

#: commands that cannot run in the test, by a regular expression on the command,
#: with the reason (reported as skipped)
ALLOW = {
    r"--dask\s+(tcp|tls|ws)://": "needs a running Dask scheduler at that address",
    r"--scheduler\s+(tcp|tls|ws)://": "needs a running Dask scheduler at that address",
    r"--scheduler\s+\S*:\d+": "needs a running Dask scheduler at that address",
}

#: commands that take long (more than about 10 s): run only under ``-m slow``; a pattern is
#: matched against the command and against "path: command"
SLOW = {
    r"^exact-khk atlas(?!.*--systems)": "the atlas of the whole catalogue (35 systems at two step sizes: "
                                        "about 8 minutes, --quick too)",
    r"^docs/benchmarks\.md: ": "the commands measured in the benchmarks (seconds to minutes each)",
    r"^exact-khk liouville --n ([5-9]|\d\d)": "liouville at n >= 5: 5 s over F_P, 20 s to minutes in Q(zeta_n)",
    r"^exact-khk prove --n 3": "symbolic proofs for n = 3 (about 11 CPU minutes)",
    r"^exact-khk certify .*--arith cyclo:": "certificates over Q(zeta_N) with every involution (several seconds)",
    r"^exact-khk certify --n ([6-9]|\d\d)": "certificates at n >= 6 (ten seconds and more)",
    r"^exact-khk orbit --n (\d{3,}|[6-9]\d)": "exact orbits at n >= 60",
    r"^exact-khk hard(\s|$)(?!.*--only)": "the whole hard-case catalogue (12 s wall, 10 s CPU in one run, docs/precision.md)",
    r"^exact-khk scale .*--digits": "precision searches over many precisions",
    r"^exact-khk scale .*--steps\s+200": "200 steps in eleven arithmetics",
    r"^exact-khk scale\s*$": "50 steps in eleven arithmetics up to 4096 bits",
    r"^exact-khk scale .*--steps\s+100": "100 steps in eleven arithmetics",
    r"^exact-khk sweep": "a sweep over many systems",
    r"^exact-khk certify .*--steps\s+([3-9]\d|\d{3,})": "a long certificate",
}

#: documented commands that do not (yet) end as the text implies, by a regular expression
#: on "path: command", with what is wrong (xfail, not strict: reported to the lead)
KNOWN = {}

#: a word that stands for something the reader fills in
#: a placeholder word, not a family parameter such as volterra-periodic:N=5 (a letter followed by '=')
PLACEHOLDER = re.compile(r"<[^>]+>|\.\.\.|\b(FILE|NAME|PATH|DIR|ADDRESS|URL|SEED|N|K|P)\b(?!=)")

EXIT_COMMENT = re.compile(r"exit(?:s)?(?:\s+with)?(?:\s+status)?\s*(?:=|:|->)?\s*(\d+)", re.I)


def doc_files():
    files = [ROOT / "README.md"] + sorted((ROOT / "docs").glob("**/*.md"))
    return [f for f in files if f.is_file()]


def shell_blocks(text):
    """(first line number, body) of every fenced shell block (``` or ~~~, any indent)."""
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        m = re.match(r"^(\s*)(```+|~~~+)\s*([\w+-]*)", lines[i])
        if not m:
            i += 1
            continue
        fence, lang, start = m.group(2), m.group(3).lower(), i + 1
        j = start
        while j < len(lines) and not lines[j].strip().startswith(fence):
            j += 1
        if lang in SHELL_LANGS:
            yield start + 1, lines[start:j]
        i = j + 1


def logical_lines(block):
    """Join continuation lines; yield (offset of the first line, text)."""
    buf, first = "", None
    for k, line in enumerate(block):
        if first is None:
            first = k
        if line.rstrip().endswith("\\"):
            buf += line.rstrip()[:-1] + " "
            continue
        yield first, buf + line
        buf, first = "", None
    if buf.strip():
        yield first, buf


def _split_comment(line):
    """(code, comment) with a '#' that starts a comment (not inside quotes)."""
    quote = None
    for k, ch in enumerate(line):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "'\"":
            quote = ch
        elif ch == "#" and (k == 0 or line[k - 1].isspace()):
            return line[:k], line[k + 1:]
    return line, ""


def segments(text):
    """(line, block line, command, expected exit status, verdict words its comment claims) of
    every command of the shell blocks of a text (chains split at &&, ||, ;, |; prompts and
    comments removed)."""
    for lineno, block in shell_blocks(text):
        for offset, raw in logical_lines(block):
            line = re.sub(r"^\s*(\$|>|%)\s+", "", raw)  # a prompt
            code, comment = _split_comment(line)
            m = EXIT_COMMENT.search(comment)
            expected = int(m.group(1)) if m else 0
            for segment in re.split(r"&&|\|\||;|\|", code):
                yield lineno + offset, lineno, " ".join(segment.split()), expected, claimed_words(comment)


#: verdict words a comment or the text may claim a command prints (checked in its output)
VERDICT = re.compile(r"\b(VALID|INVALID|INCONCLUSIVE|VERIFIED|NOT VERIFIED|FOUND|NONE)\b")


def claimed_words(text):
    """The verdict words a comment claims, e.g. "# VALID, exit 0" -> ["VALID"]."""
    return VERDICT.findall(text or "")


def commands_in(text):
    """[(line, block line, command, expected exit status, claimed verdict words)] of the exact-khk
    commands in the shell blocks of a text."""
    out = []
    for line, block, seg, expected, claims in segments(text):
        seg = re.sub(r"^(python3?|\S*/python3?) -m exact_khk\b", "exact-khk", seg)
        if re.match(r"^(\w+=\S*\s+)*exact-khk(\s|$)", seg):
            out.append((line, block, seg, expected, claims))
    return out


def prose(text):
    """The text with its fenced blocks blanked (line numbers kept): what inline code sits in."""
    lines, fence = text.splitlines(), None
    for k, line in enumerate(lines):
        m = re.match(r"^\s*(```+|~~~+)", line)
        if fence or m:
            fence = None if fence and m and m.group(1).startswith(fence) else (fence or m.group(1))
            lines[k] = ""
    return "\n".join(lines)


#: a command in inline code: ``exact-khk`` (or ``python -m exact_khk``) and its arguments
INLINE_COMMAND = re.compile(r"^(?:\w+=\S*\s+)*(?:exact-khk|python3? -m exact_khk)(?:\s|$)")
#: an exit status stated right after an inline command: "`...` (exit 4)", "`...` exits 2", "`...`: exit status 1"
INLINE_EXIT = re.compile(r"^[\s,:;]*\(?\s*exit(?:s)?(?:\s+with)?(?:\s+status)?\s*(\d+)", re.I)


def inline_commands_in(text):
    """[(line, command, expected exit status)] of the ``exact-khk ...`` commands in the inline
    code of a text's prose (which may run over a line break); the exit status is 0 unless the
    words right after the span state one (``(exit 4)``, ``exits 2``)."""
    out, body = [], prose(text)
    for m in re.finditer(r"`([^`]+)`", body):
        code = " ".join(m.group(1).split())
        if INLINE_COMMAND.match(code):
            code = re.sub(r"^(python3?) -m exact_khk\b", "exact-khk", code)
            stated = INLINE_EXIT.match(body[m.end():m.end() + 60])
            out.append((body.count("\n", 0, m.start()) + 1, code, int(stated.group(1)) if stated else 0))
    return out


def extract():
    """[(file, line, block line, command, expected exit status, claimed verdict words)] for every
    documented command:
    those of the shell blocks (block line: the block's first line, whose commands share one
    working folder), then those of inline code, each (command, exit status) once (block line
    None: a folder of its own)."""
    out, seen = [], set()
    for path in doc_files():
        text, name = path.read_text(encoding="utf-8"), path.relative_to(ROOT).as_posix()
        out += [(name, *item) for item in commands_in(text)]
    seen = {(c[3], c[4]) for c in out}
    for path in doc_files():
        name = path.relative_to(ROOT).as_posix()
        for line, command, expected in inline_commands_in(path.read_text(encoding="utf-8")):
            if (command, expected) not in seen:
                seen.add((command, expected))
                out.append((name, line, None, command, expected, []))
    return out


COMMANDS = extract()


def _reason(table, command, path=None):
    """The reason of the first pattern of ``table`` that matches the command (or "path: command")."""
    texts = [command] + ([f"{path}: {command}"] if path else [])
    return next((why for pattern, why in table.items() if any(re.search(pattern, s) for s in texts)), None)


def _param(item):
    path, line, block, command, expected, claims = item
    marks = []
    if _reason(SLOW, command, path):
        marks.append(pytest.mark.slow)
    known = _reason(KNOWN, f"{path}: {command}")
    if known:
        marks.append(pytest.mark.xfail(strict=False, reason=known))
    return pytest.param(command, expected, claims, path, line, block, marks=marks, id=f"{path}:{line}: {command[:70]}")


def test_commands_were_found():
    assert len(COMMANDS) >= 10, COMMANDS
    assert any(c[3].startswith("exact-khk certify") for c in COMMANDS)


def test_allow_list_reasons_are_given():
    assert all(why.strip() for why in list(ALLOW.values()) + list(SLOW.values()) + list(KNOWN.values()))


_FOLDERS = {}


def _block_folder(path, block, factory):
    """One working folder per shell block, shared by its commands in order (``certify --json
    cert.json`` then ``verify cert.json``), with the repository's files linked in so that
    paths such as docs/examples/x.toml resolve."""
    key = (path, block)
    if key not in _FOLDERS:
        folder = factory.mktemp("docs")
        for entry in ROOT.iterdir():
            if not entry.name.startswith(".") and entry.name not in ("out", "build", "dist"):
                (folder / entry.name).symlink_to(entry)
        _FOLDERS[key] = folder
    return _FOLDERS[key]


@pytest.mark.parametrize("command, expected, claims, path, line, block", [_param(c) for c in COMMANDS])
def test_documented_command(command, expected, claims, path, line, block, tmp_path_factory, monkeypatch, capsys):
    why = _reason(ALLOW, command, path)
    if why:
        pytest.skip(f"{path}:{line}: not run here: {why}")
    argv = shlex.split(command)
    while argv and re.match(r"^\w+=", argv[0]):  # VAR=value exact-khk ...
        name, _, value = argv.pop(0).partition("=")
        monkeypatch.setenv(name, value)
    assert argv[0] == "exact-khk"
    unfilled = [a for a in argv[1:] if PLACEHOLDER.search(a) and not a.startswith("-")]
    assert not unfilled, (f"{path}:{line}: {command!r} has a placeholder {unfilled}; list it in ALLOW "
                          f"(tests/test_docs_commands.py) with the reason it cannot run")
    monkeypatch.chdir(_block_folder(path, block if block is not None else f"inline {line}", tmp_path_factory))
    code = main(argv[1:])
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    assert code == expected, f"{path}:{line}: {command!r} exited {code}, the text implies {expected}: {err[-500:]}"
    missing = [w for w in claims if not re.search(rf"\b{w}\b", out + err)]
    assert not missing, f"{path}:{line}: {command!r}: the text claims {missing} in its output: {(out + err)[-500:]}"


def test_extraction_rules():
    text = "\n".join([
        "Intro", "```bash", "$ exact-khk orbit --steps 2        # comment", "exact-khk certify \\", "  --steps 2",
        "pip install . && exact-khk systems | head", "python -m exact_khk --version",
        "exact-khk certify --eps 0  # exit 2", "echo hi", "```", "```python", "exact-khk not-a-shell-block", "```",
        "  ```sh", "  EXACT_KHK_MAX_MEMORY=8G exact-khk orbit", "  ```"])
    found = [(command, expected) for _, _, command, expected, _ in commands_in(text)]
    assert found == [("exact-khk orbit --steps 2", 0), ("exact-khk certify --steps 2", 0),
                     ("exact-khk systems", 0), ("exact-khk --version", 0), ("exact-khk certify --eps 0", 2),
                     ("EXACT_KHK_MAX_MEMORY=8G exact-khk orbit", 0)]


def test_inline_extraction_rules():
    """Inline code in prose: commands found (over a line break too), exit statuses stated right
    after the span, fenced blocks and other code spans left alone, verdict words of comments."""
    text = "\n".join([
        "Run `exact-khk orbit --steps 2` first; `exact-khk certify --eps 0` (exit 2) is refused,",
        "and `python -m exact_khk certify",
        "--steps 3` exits 4 here. `exact-khk:` is an error prefix, `exact_khk.certify` a function.",
        "```bash", "exact-khk in-a-block  # VALID, exit 0", "```", "`exact-khk systems`"])
    assert [(c, e) for _, c, e in inline_commands_in(text)] == [
        ("exact-khk orbit --steps 2", 0), ("exact-khk certify --eps 0", 2), ("exact-khk certify --steps 3", 4),
        ("exact-khk systems", 0)]
    assert [line for line, _, _ in inline_commands_in(text)] == [1, 1, 2, 7]
    assert [c[4] for c in commands_in(text)] == [["VALID"]]
    assert claimed_words("# last line VERIFIED: ..., exit 0") == ["VERIFIED"]
    assert claimed_words("# exit 4: an orbit meets a singular step") == []


def test_inline_commands_were_found():
    inline = [c for c in COMMANDS if c[2] is None]
    assert len(inline) >= 10, inline
    assert any(c[0] == "README.md" for c in inline) and any(c[0].startswith("docs/") for c in inline)


# --- documented scripts: ``python scripts/NAME.py ...`` --------------------------------

#: a documented script command: optional VAR=value assignments, python, a script of scripts/
SCRIPT = re.compile(r"^(?:\w+=\S*\s+)*python3?\s+scripts/\w+\.py\b")

#: words in documented script commands that stand for a source tree: the test passes the
#: copy of the repository it runs in (so the tree is compared with itself)
TREE_PLACEHOLDER = "OLD_TREE"


def script_commands_in(text):
    """[(line, command)] of the ``python scripts/NAME.py ...`` commands in a text: in shell
    blocks, and in inline code (which may run over a line break)."""
    out = [(line, seg) for line, _, seg, _, _ in segments(text) if SCRIPT.match(seg)]
    body = prose(text)
    for m in re.finditer(r"`([^`]+)`", body):
        code = " ".join(m.group(1).split())
        if SCRIPT.match(code):
            out.append((body.count("\n", 0, m.start()) + 1, code))
    return out


def extract_scripts():
    """[(file, line, command)] of every documented script command, each command once."""
    seen, out = set(), []
    for path in doc_files():
        for line, command in script_commands_in(path.read_text(encoding="utf-8")):
            if command not in seen:
                seen.add(command)
                out.append((path.relative_to(ROOT).as_posix(), line, command))
    return out


SCRIPT_COMMANDS = extract_scripts()


def _script_argv(command, tree):
    """(environment additions, argv) of a documented script command, run by this interpreter."""
    words, env = shlex.split(command), {}
    while re.match(r"^\w+=", words[0]):
        name, _, value = words.pop(0).partition("=")
        env[name] = value
    return env, [sys.executable] + [str(tree) if w == TREE_PLACEHOLDER else w for w in words[1:]]


def _script_param(item, *marks):
    path, line, command = item
    return pytest.param(command, path, line, marks=marks, id=f"{path}:{line}: {command[:70]}")


def test_script_commands_were_found():
    scripts = {shlex.split(c)[[w.startswith("scripts/") for w in shlex.split(c)].index(True)]
               for _, _, c in SCRIPT_COMMANDS}
    assert len(SCRIPT_COMMANDS) >= 10 and {"scripts/bench.py", "scripts/hard_cases.py"} <= scripts, scripts
    assert all((ROOT / s).is_file() for s in scripts), scripts


@pytest.mark.parametrize("command, path, line", [_script_param(c) for c in SCRIPT_COMMANDS])
def test_documented_script_options(command, path, line):
    """Quick check of every documented script command: the script starts and its argument
    parser knows every option the command gives (``--help`` after the documented
    arguments: argparse converts the values before it and prints the options)."""
    code, err, unknown = _options_check(command)
    assert code == 0 and "Traceback" not in err, f"{path}:{line}: {err[-800:]}"
    assert not unknown, f"{path}:{line}: {command!r}: options not in the script's --help: {unknown}"


def _options_check(command):
    """(exit status, stderr, options the script's --help does not list) of a script command."""
    env, argv = _script_argv(command, ROOT)
    res = subprocess.run(argv + ["--help"], cwd=ROOT, env={**os.environ, **env}, capture_output=True,
                         text=True, timeout=120)
    unknown = [w.split("=")[0] for w in argv if w.startswith("--") and w.split("=")[0] not in res.stdout]
    return res.returncode, res.stderr, unknown


def test_script_options_check_can_fail():
    """The negative controls of the quick check: an option the script does not have, a value
    its parser refuses, a script that does not exist."""
    assert _options_check("python3 scripts/bench_exact.py --no-such-option 3")[2] == ["--no-such-option"]
    assert _options_check("python3 scripts/bench_exact.py --bits notanumber")[0] == 2
    assert _options_check("python3 scripts/no_such_script.py")[0] != 0


def _repo_copy(folder):
    """A copy of the repository's sources (not its virtual environments or caches), so that a
    script that writes into docs/ or tests/data/ writes into the copy."""
    dst = folder / "repo"
    shutil.copytree(ROOT, dst, ignore=shutil.ignore_patterns(".*", "__pycache__", "*.egg-info", "out",
                                                              "build", "dist"))
    return dst


@pytest.mark.slow
@pytest.mark.parametrize("command, path, line", [_script_param(c) for c in SCRIPT_COMMANDS])
def test_documented_script_runs(command, path, line, tmp_path):
    """Every documented script command, as shown (benchmarks and studies: minutes to half an
    hour each), in a copy of the repository; it must exit with status 0."""
    tree = _repo_copy(tmp_path)
    env, argv = _script_argv(command, tree)
    res = subprocess.run(argv, cwd=tree, env={**os.environ, **env}, capture_output=True, text=True,
                         timeout=3 * 3600)
    assert res.returncode == 0, f"{path}:{line}: {command!r} exited {res.returncode}: {res.stderr[-1500:]}"
    assert "Traceback" not in res.stderr
