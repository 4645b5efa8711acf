"""Writing the scripts' outputs: atomically, or checked against the file already there.

No exact_khk import: the golden-data generators use this and must stay independent of
the code they test.
"""

from __future__ import annotations

import json
import os
import pathlib
import tempfile


def child_cpu() -> float:
    """CPU seconds (user + system) used so far by this process's finished children."""
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def write_atomic(path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` through a temporary file in the same folder,
    renamed into place: an interrupted run leaves the old file, never half a new one."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix=path.name, dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def write_or_check(path, data: dict, check: bool, key: str = "cases") -> int:
    """Write ``data`` as indented JSON to ``path`` (exit status 0), or with ``check``
    compare its ``key`` entry with the file's (0 if equal, 1 if not: the committed golden
    data is not what the independent route gives now); prints what it did."""
    path = pathlib.Path(path)
    if not check:
        write_atomic(path, json.dumps(data, indent=1) + "\n")
        print(f"wrote {len(data[key])} {key} to {path}")
        return 0
    old = json.loads(path.read_text(encoding="utf-8"))[key]
    if old == data[key]:
        print(f"{path}: the {len(old)} {key} agree")
        return 0
    differ = [k for k, (a, b) in enumerate(zip(old, data[key])) if a != b]
    print(f"{path}: {key} DIFFER (file {len(old)}, now {len(data[key])}; differing at {differ[:10]})")
    return 1
