#!/usr/bin/env python3
"""Runs a command and checks its exit code and its output, both.

CTest's PASS_REGULAR_EXPRESSION alone ignores the exit code (a command that
prints the expected line and then crashes passes), so command-line tests go
through this:

  cli_expect.py [--code N] [--match REGEX]... [--absent REGEX]... [--fifo PATH]
                [--timeout S] [--signal NAME:S] -- COMMAND ARGS...

--code N      the exit code the command must end with (default 0)
--match R     a regular expression its stdout+stderr must contain (re.S)
--absent R    one it must not contain
--fifo PATH   make PATH a FIFO before running (hostile-input tests)
--timeout S   fail if the command has not ended after S seconds (default 120):
              a command that hangs on hostile input is a failure, not a stuck CI
--signal NAME:S  send signal NAME (TERM, INT, HUP) S seconds after the start
"""
import argparse
import os
import re
import signal
import subprocess
import sys


def main():
    if "--" not in sys.argv:
        print(__doc__, file=sys.stderr)
        return 2
    split = sys.argv.index("--")
    p = argparse.ArgumentParser()
    p.add_argument("--code", type=int, default=0)
    p.add_argument("--match", action="append", default=[])
    p.add_argument("--absent", action="append", default=[])
    p.add_argument("--fifo", action="append", default=[])
    p.add_argument("--timeout", type=float, default=120)
    p.add_argument("--signal")
    a = p.parse_args(sys.argv[1:split])
    cmd = sys.argv[split + 1:]
    for f in a.fifo:
        if os.path.lexists(f):
            os.remove(f)
        os.mkfifo(f)
    sig, sig_after = None, None
    if a.signal:
        name, _, after = a.signal.partition(":")
        sig, sig_after = signal.Signals["SIG" + name], float(after or 0)
    r = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         stdin=subprocess.DEVNULL)
    try:
        if sig is not None:
            try:
                r.wait(timeout=sig_after)
            except subprocess.TimeoutExpired:
                r.send_signal(sig)
        stdout, _ = r.communicate(timeout=a.timeout)
    except subprocess.TimeoutExpired:
        r.kill()
        print(f"cli_expect: {cmd[0]} did not end within {a.timeout} s", file=sys.stderr)
        return 1
    out = stdout.decode(errors="replace")
    sys.stdout.write(out)
    ok = True
    if r.returncode != a.code:
        print(f"cli_expect: exit code {r.returncode}, expected {a.code}", file=sys.stderr)
        ok = False
    for m in a.match:
        if not re.search(m, out, re.S):
            print(f"cli_expect: output lacks /{m}/", file=sys.stderr)
            ok = False
    for m in a.absent:
        if re.search(m, out, re.S):
            print(f"cli_expect: output has /{m}/", file=sys.stderr)
            ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
