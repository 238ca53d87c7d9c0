"""README.md: the commands CI runs, no hand-typed results, no machine-specific wording."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")

#: The Quick start commands; .ci/run executes the second ```sh block as the test command.
QUICK_START = [
    "python3 -m venv .venv && . .venv/bin/activate && pip install -e . && snakemake --cores all",
    'python3 -m venv .venv && . .venv/bin/activate && pip install -e ".[test]" && python -m pytest',
]


def test_the_quick_start_blocks_are_the_two_commands():
    assert [b.strip() for b in re.findall(r"```sh\n(.*?)```", README, re.S)] == QUICK_START


def test_no_hand_typed_statistics_or_machine_wording():
    # Results are read from the files the pipeline writes (stats.md, the figures).
    patterns = [r"F\(\d+, ?\d+\) ?=", r"\bp ?[=<] ?\.?\d", r"\bR\^2 \d", r"this (2-core )?machine"]
    found = [m.group(0) for p in patterns for m in re.finditer(p, README)]
    assert not found, found


def test_readers_are_warned_about_the_method_na():
    assert "keep_default_na=False" in README and "read_table" in README


def test_the_documents_it_links_exist():
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", README)
    missing = [link for link in links if not link.startswith("http") and not (ROOT / link).exists()]
    assert links and not missing, missing


def slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def test_the_sections_it_links_exist():
    anchors = re.findall(r"\]\(([^)#]+)#([^)]+)\)", README)
    for page, anchor in anchors:
        headings = re.findall(r"^#+ (.+)$", (ROOT / page).read_text(encoding="utf-8"), re.M)
        assert anchor in {slug(h) for h in headings}, f"{page}#{anchor}"


def test_the_build_it_describes_is_the_configs():
    # The counts beside the measured build times are the configs' own, so a variant added
    # to a config makes the README's time visibly stale rather than silently wrong.
    import yaml

    default = yaml.safe_load((ROOT / "config" / "config.yaml").read_text(encoding="utf-8"))
    ci = yaml.safe_load((ROOT / "config" / "ci.yaml").read_text(encoding="utf-8"))
    text = " ".join(README.split())
    variants = len(default["robustness"]["variants"])
    assert f"with the {variants} robustness variants of `config/config.yaml`" in text
    assert f"under each of {variants} modelling variants" in text
    participants = ci["simulation"]["participants"]
    runs, each = len(ci["robustness"]["run"]), ci["robustness"]["participants"]
    assert f"({participants} participants; {runs} variants of {each})" in text
