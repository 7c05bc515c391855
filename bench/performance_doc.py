"""docs/performance.md kept current by the benches: each rewrites its own marked section with its
latest figures (git keeps what they were), and the README's headline table is copied from it.

    <!-- bench:NAME -->  ...what the bench wrote last...  <!-- /bench:NAME -->

``write_section`` replaces a section's text; ``write_rows`` replaces only a bench's own rows of
a shared table (the headline: the example scenes' rows from bench_auto_volumes.py, the random
suite's median from bench_auto_lit.py). ``python bench/performance_doc.py --readme`` (also run
after every change to the headline) copies the headline into the README's marked section.
"""
from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PERFORMANCE = ROOT / "docs" / "performance.md"
README = ROOT / "README.md"
#: The README's one table: auto against the file as an artist has it, at these counts.
HEADLINE = "headline"
HEADLINE_COUNTS = (16, 64, 256)
HEADLINE_HEADER = ("scene", *(f"{spp} spp" for spp in HEADLINE_COUNTS))


def _markers(name: str) -> tuple[str, str]:
    return f"<!-- bench:{name} -->", f"<!-- /bench:{name} -->"


def read_section(name: str, path: Path = PERFORMANCE) -> str:
    """The text of section ``name`` (without its markers); KeyError where it has none."""
    begin, end = _markers(name)
    text = Path(path).read_text(encoding="utf-8")
    found = re.search(re.escape(begin) + r"\n(.*?)" + re.escape(end), text, re.S)
    if found is None:
        raise KeyError(f"{path} has no section '{name}'")
    return found.group(1)


def write_section(name: str, body: str, path: Path = PERFORMANCE, title: str | None = None) -> None:
    """Section ``name`` of ``path`` becomes ``body``; a section not there yet is added at the
    end, under ``title`` when given. Written through a temporary name."""
    begin, end = _markers(name)
    path = Path(path)
    text = path.read_text(encoding="utf-8") if path.exists() else ""
    block = f"{begin}\n{body.rstrip()}\n{end}"
    if begin in text:
        text = re.sub(re.escape(begin) + r"\n.*?" + re.escape(end), lambda _: block, text, flags=re.S)
    else:
        text = text.rstrip() + ("\n\n" if text else "") + (f"## {title}\n\n" if title else "") + block + "\n"
    temporary = path.with_name(f".{path.name}.partial")
    temporary.write_text(text, encoding="utf-8")
    temporary.replace(path)
    if name == HEADLINE and path == PERFORMANCE:
        fill_readme()


def write_bench_output(name: str, title: str, script: str, argv, lines: list[str]) -> None:
    """Section ``name`` becomes a bench's printed ``lines`` under the command that made them."""
    command = f"bench/{script} " + " ".join(sys.argv[1:] if argv is None else argv)
    write_section(name, f"`{command.strip()}`\n\n```\n" + "\n".join(lines) + "\n```", title=title)


def _table(header, rows) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return "\n".join(lines + ["| " + " | ".join(row) + " |" for row in rows])


def table_rows(body: str) -> list[list[str]]:
    """The rows of a Markdown table (header and rule left out)."""
    rows = [line.strip().strip("|").split("|") for line in body.splitlines() if line.startswith("|")]
    return [[cell.strip() for cell in row] for row in rows[2:]]


def write_rows(name: str, header, rows: list[list[str]], path: Path = PERFORMANCE, note: str = "") -> None:
    """Section ``name`` as a table of ``header``: ``rows`` replace the rows with the same first
    cell, the others stay (each bench owns its rows). ``note`` follows the table."""
    try:
        kept = table_rows(read_section(name, path))
    except (KeyError, FileNotFoundError):
        kept = []
    mine = {row[0] for row in rows}
    table = _table(header, [row for row in kept if row[0] not in mine] + list(rows))
    write_section(name, table + (f"\n\n{note}" if note else ""), path)


def speedup_text(speedup: dict | None) -> str:
    """A cell: the equal-quality speedup, '*' where it was read beyond the curve, '-' if none."""
    if not speedup or speedup.get("value") is None:
        return "-"
    return f"{speedup['value']:.2f}x" + ("*" if speedup.get("extrapolated") else "")


def fill_readme(readme: Path = README, performance: Path = PERFORMANCE) -> None:
    """Copy the headline section of ``performance`` into the README's marked section."""
    write_section(HEADLINE, read_section(HEADLINE, performance), readme)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--readme", action="store_true", help="copy the headline table into README.md")
    args = parser.parse_args(argv)
    if args.readme:
        fill_readme()
    return 0


if __name__ == "__main__":
    sys.exit(main())
