"""Formatting shared by scripts/performance_doc.py and its Google Benchmark tables."""

import re


def number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def ns(value):
    if value is None or value <= 0:
        return "-"
    if value >= 10000:
        return f"{value:,.0f}".replace(",", " ")
    return f"{value:.0f}" if value >= 100 else f"{value:.1f}"


def pct(fraction, digits=2):
    return "-" if fraction is None else f"{100.0 * fraction:.{digits}f}"


def mm(value, digits=1):
    return "-" if value is None else f"{value:.{digits}f}"


def size(nbytes):
    if not nbytes:
        return "-"
    if nbytes >= 1 << 20:
        return f"{nbytes / (1 << 20):.1f} MiB"
    return f"{nbytes / 1024:.0f} KiB"


def span(values, fmt):
    values = [v for v in values if v is not None]
    if not values:
        return "-"
    lo, hi = min(values), max(values)
    return fmt(lo) if fmt(lo) == fmt(hi) else f"{fmt(lo)}–{fmt(hi)}"


def file_safe(text):
    return re.sub(r"[^A-Za-z0-9]", "_", text)


def pair(a, b, fmt=ns):
    return "-" if a is None and b is None else f"{fmt(a)} / {fmt(b)}"


class Doc:
    def __init__(self, info, out):
        self.info = info
        self.out = out
        self.lines = []

    def add(self, *lines):
        self.lines.extend(lines)

    def machine(self):
        i = self.info
        return (f"{i.get('cpu', '?')}, {i.get('cores', '?')} cores, {i.get('compiler', '?')}, "
                f"preset {i.get('preset', 'bench')}")

    def source(self, what, commit=None, date=None):
        """The line under every table: machine, command and commit (a program re-run alone
        gives its own commit and date)."""
        i = self.info
        command = i.get('command', '?')
        if commit:
            command = f"scripts/bench.sh --gbench-only {what}"
            commit = f"`{commit}`"
        else:
            commit = f"`{i.get('commit', '?')}`"
            if i.get("worktree") == "modified":
                commit += " with local changes"
        self.add("", f"*{self.machine()}; `{command}` ({what}); commit {commit}; "
                 f"{date or i.get('date', '')}.*", "")
