"""``exact-khk verify CERT.json [--json]``: re-check a saved certificate (a thin view of
:func:`exact_khk.certification.verify.verify`).

Exit status: 0 VERIFIED (every record, the orbit, the integral values and the
status re-derived and as recorded, whatever the status is); 1 NOT VERIFIED (a
record or result differs — a tampered certificate —, or the certificate was
computed in an inexact arithmetic and cannot be re-checked exactly); 2 an
unreadable or malformed file (one line on stderr); 4 PARTIALLY VERIFIED (all that
was re-derived agrees, but some records were not re-checked).

The ``identity:`` records of ``certify --identities`` are re-derived at the verifier's own random
draws (``--seed`` makes them reproducible), the ``proof:`` records of ``certify --prove`` in SymPy
up to dimension 3 (docs/verify.md).
"""

from __future__ import annotations

import json
import sys

from exact_khk.certification.verify import verify
from exact_khk.cli.options import add_json_option, check_output, write_json
from exact_khk.errors import InputError
from exact_khk.parsing import read_text_file

#: the largest certificate file read (bytes)
MAX_CERTIFICATE = 200_000_000


def register(sub):
    p = sub.add_parser("verify", help="re-derive every record of a saved certificate (orbit, claims, controls, "
                       "status) by a separate minimal exact code path",
                       description="Re-derive a certificate written by 'exact-khk certify --json PATH' from its "
                       "own data: every orbit point is the Kahan step of the previous one, every integral value "
                       "is recomputed, the records are exactly those the system and options imply, and each "
                       "record's statement, evidence, holds, residual and applicability are recomputed, then the "
                       "status. Plain exact arithmetic, independent of the library's solvers and certification "
                       "engines; the records of --identities at its own random draws over F_P, those of --prove "
                       "in SymPy up to dimension 3 (docs/verify.md). Exit status 0 VERIFIED, 1 NOT VERIFIED, "
                       "2 unreadable or malformed file, 4 PARTIALLY VERIFIED (some records not re-checked).")
    p.add_argument("certificate", metavar="CERT.json", nargs="?", help="the certificate file")
    p.add_argument("--seed", type=int, metavar="S",
                   help="seed of the verifier's own random draws over F_P for the certificate's 'identity:' "
                        "records (default: fresh from the operating system; the report states the seed used)")
    add_json_option(p, "the report")
    p.set_defaults(func=cmd_verify)


def read_certificate(path) -> dict:
    """The JSON object in ``path``; InputError (one line, naming the file) if it cannot be read
    (missing, a folder, a device or a pipe, beyond :data:`MAX_CERTIFICATE` bytes, not UTF-8 JSON)."""
    text = read_text_file(path, "certificate file", MAX_CERTIFICATE)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{path}: not valid JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})") from None
    except (ValueError, RecursionError) as exc:  # e.g. an integer beyond a digit limit, nesting too deep
        raise InputError(f"{path}: not a readable JSON certificate ({type(exc).__name__}: {exc})") from None
    if not isinstance(data, dict):
        raise InputError(f"{path}: expected a JSON object (a certificate), got a {type(data).__name__}")
    return data


def cmd_verify(args):
    if args.certificate is None and args.json not in (None, "-"):
        # the spelling from before --json took a PATH: 'verify --json CERT.json'
        print(f"exact-khk: note: 'verify --json {args.json}' is deprecated (--json now takes an output PATH); "
              f"write 'verify {args.json} --json'", file=sys.stderr)
        args.certificate, args.json = args.json, "-"
    if args.certificate is None:
        raise InputError("verify: the following arguments are required: CERT.json")
    check_output(args.json)
    data = read_certificate(args.certificate)
    try:
        report = verify(data, seed=args.seed)
    except InputError as exc:
        raise InputError(f"{args.certificate}: {exc}") from None
    if args.json is not None:
        write_json(report.to_json(), args.json)
    if args.json != "-":
        print(report.summary())
    return report.exit_status
