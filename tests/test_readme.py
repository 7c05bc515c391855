"""The README is for the people who use the extension: short, its first sentence a sentence,
how to install it and the panel near the top, and every file it links to there."""
from __future__ import annotations

import re

from conftest import ROOT

README = (ROOT / "README.md").read_text(encoding="utf-8")


def test_it_is_short_and_opens_with_one_plain_sentence():
    lines = README.splitlines()
    assert len(lines) <= 250
    opening = " ".join(line for line in lines[1:] if line and not line.startswith("#")).split(". ")[0]
    assert len(opening.split()) <= 30, opening


def test_install_and_the_panel_come_first():
    head = "\n".join(README.splitlines()[:60])
    assert "## Install" in head and "python3 run.py build" in head
    assert "Install from Disk" in head and "Auto Volumes" in head and "Render Properties" in head


def test_every_local_link_exists():
    links = re.findall(r"\]\(([^)#]+)\)", README)
    local = [link for link in links if "://" not in link]
    assert local and [link for link in local if not (ROOT / link).exists()] == []
