"""docs/performance.md kept by the benches (``bench/performance_doc.py``): a bench rewrites only
its own section (or its own rows of a shared table), and the README's headline table is the
one in docs/performance.md."""
from __future__ import annotations

import sys

from conftest import ROOT

sys.path.insert(0, str(ROOT / "bench"))
import performance_doc  # noqa: E402


def test_a_bench_rewrites_its_own_section_and_nothing_else(tmp_path):
    doc = tmp_path / "performance.md"
    doc.write_text("# Performance\n\nWhat it measures.\n")
    performance_doc.write_section("one", "first figures", doc, title="One")
    performance_doc.write_section("two", "other figures", doc)
    performance_doc.write_section("one", "newer figures\nwith $1 and \\1 kept", doc)
    text = doc.read_text()
    assert text.startswith("# Performance\n\nWhat it measures.\n\n## One\n\n<!-- bench:one -->")
    assert performance_doc.read_section("one", doc) == "newer figures\nwith $1 and \\1 kept\n"
    assert performance_doc.read_section("two", doc) == "other figures\n"
    assert "first figures" not in text and text.count("<!-- bench:one -->") == 1
    assert not list(tmp_path.glob(".*partial*"))


def test_a_shared_table_keeps_the_rows_of_other_benches(tmp_path):
    doc = tmp_path / "performance.md"
    header = ("scene", "16 spp")
    performance_doc.write_rows("table", header, [["road", "1.1x"], ["statue", "2.0x"]], doc)
    performance_doc.write_rows("table", header, [["random suite", "1.8x"]], doc, note="a note")
    performance_doc.write_rows("table", header, [["road", "1.3x"]], doc, note="a note")
    assert performance_doc.table_rows(performance_doc.read_section("table", doc)) == [
        ["statue", "2.0x"], ["random suite", "1.8x"], ["road", "1.3x"]]
    assert performance_doc.read_section("table", doc).endswith("\n\na note\n")


def test_the_readme_headline_is_docs_performance_s():
    headline = performance_doc.read_section(performance_doc.HEADLINE)
    assert performance_doc.read_section(performance_doc.HEADLINE, performance_doc.README) == headline
    header = headline.splitlines()[0]
    assert all(f"{spp} spp" in header for spp in performance_doc.HEADLINE_COUNTS)
