"""The HTML report in a real browser: it opens on the results and the figures.

The workflow runs on a temporary copy with a small synthetic dataset
(``--config simulate=false``), builds ``report.html``, and Debian's chromium, headless,
renders it: the test reads the rendered page (``--dump-dom``) and writes a screenshot of
the first screen for a person to look at (its path is printed). Expected numbers are
read from the ``stats.csv`` that the same run wrote, rendered by casa_core.stats.apa.
"""

from __future__ import annotations

import html
import shutil
import subprocess
import tempfile

import pytest

from casa_core.cli import main
from casa_core.io import read_table
from casa_core.io.atomic import write_csv
from casa_core.stats import STATS_COLUMNS, apa
from tests.io.test_logs_synthetic import write_dataset
from tests.workflow.test_workflow import copy_workflow, snakemake

CHROMIUM = shutil.which("chromium")
needs_chromium = pytest.mark.skipif(
    CHROMIUM is None, reason="chromium is not installed (apt-get install -y chromium)"
)
# The flags this machine needs: no sandbox as root, no GPU, no network chatter.
FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def chromium(url: str, *args: str) -> subprocess.CompletedProcess:
    with tempfile.TemporaryDirectory() as profile:
        return subprocess.run(
            [CHROMIUM, *FLAGS, f"--user-data-dir={profile}", *args, url],
            capture_output=True,
            text=True,
            timeout=120,
        )


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """A report built from the whole default target on a three-participant dataset."""
    repo = copy_workflow(tmp_path_factory.mktemp("report"))
    write_dataset(repo / "data" / "raw" / "pilot", participants=("p01", "p02", "p03"))
    run = snakemake(repo, "--cores", "2", "--config", "simulate=false")
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    built = snakemake(repo, "--report", "report.html", "--config", "simulate=false")
    assert built.returncode == 0, built.stdout[-3000:] + built.stderr[-3000:]
    return repo


@pytest.fixture(scope="module")
def page(report) -> str:
    """The rendered report's app (what React drew), without the report's data scripts."""
    url = (report / "report.html").as_uri()
    dom = chromium(url, "--virtual-time-budget=10000", "--dump-dom").stdout
    start = dom.index('<div id="app">')
    # The data scripts after the app hold the landing page as JSON text too: skip them.
    return dom[start : dom.index("<script", start)]


@pytest.mark.pipeline
@needs_chromium
def test_the_landing_page_opens_on_results_then_figures_stats_tables_workflow(report, page):
    stats = read_table(report / "data" / "processed" / "pilot" / "stats.csv")
    h1 = stats[(stats["hypothesis"] == "H1") & (stats["metric"] == "error")]
    anova = apa.result(h1[h1["analysis"] == "anova"].iloc[0])
    within = apa.result(h1[h1["analysis"] == "rm_anova"].iloc[0])
    order = [
        "Claims of the paper on dataset pilot",  # results.md: a verdict per claim
        "Results of dataset pilot",  # the summary from stats.csv
        f"ANOVA: {anova}",
        f"repeated-measures ANOVA: {within}",
        "Objective metrics of dataset pilot",  # a figure's caption
        "Likert answers (1-7) of dataset pilot",
        "The scene of the study",
        "CASA user study: statistics",  # stats.md, rendered
        "pilot: trials.csv",
        "pilot: validation.csv",
        'id="rulegraph"',  # the workflow, last
    ]
    # The DOM is serialized HTML: "p < .001" reads "p &lt; .001" there.
    where = [page.find(text if text.startswith("id=") else html.escape(text)) for text in order]
    missing = [text for text, at in zip(order, where, strict=True) if at < 0]
    assert not missing, f"not on the landing page: {missing}"
    assert where == sorted(where), f"out of order: {sorted(zip(where, order, strict=True))}"
    # The results and the figures share the first screen: two columns of one grid.
    grid = page[page.index('class="casa-grid"') : page.index("CASA user study: statistics")]
    assert "Results of dataset pilot" in grid and "<h2>Figures</h2>" in grid
    # Every figure is drawn inline from the report's own data (it is self-contained).
    assert page.count('src="data:image/png') == 3  # objective, Likert, scene
    # The tables are browsable: the filter box was added to each.
    assert page.count('placeholder="filter rows"') == 2


@pytest.mark.pipeline
@needs_chromium
def test_screenshot_of_the_first_screen(report, page, tmp_path_factory):
    shot = tmp_path_factory.mktemp("screenshot") / "report.png"
    url = (report / "report.html").as_uri()
    result = chromium(
        url, "--virtual-time-budget=10000", f"--screenshot={shot}", "--window-size=1400,1000"
    )
    assert shot.is_file(), result.stderr[-2000:]
    print(f"report screenshot: {shot}")
    assert shot.read_bytes()[:4] == b"\x89PNG" and shot.stat().st_size > 50_000


@pytest.mark.pipeline
@needs_chromium
def test_the_report_pages_exist_for_the_menu_too(report):
    pages = report / "data" / "report" / "pilot"
    names = sorted(p.name for p in pages.iterdir())
    expected = ["results", "stats", "summary", "trials", "validation"]
    assert names == [f"{name}.html" for name in expected]
    summary = (report / "data" / "processed" / "pilot" / "summary.md").read_text()
    assert summary.startswith("# Results of dataset pilot")
    # The landing page is embedded in a <script> of the report: none may end it early.
    for path in pages.iterdir():
        assert "</script" not in path.read_text(encoding="utf-8").lower(), path.name


ANOVA_ROW = dict.fromkeys(STATS_COLUMNS, float("nan")) | {
    "hypothesis": "H1",
    "analysis": "anova",
    "task": "known_goal",
    "metric": "error",
    "term": "method",
    "comparison": "",
    "statistic": 41.19,
    "df1": 2.0,
    "df2": 9.0,
    "p": 3.0e-5,
    "effect_size": 0.9015,
    "note": "",
}


def test_cli_summary_and_table_pages(tmp_path, capsys):
    import pandas as pd

    stats = tmp_path / "stats.csv"
    write_csv(stats, pd.DataFrame([ANOVA_ROW]))
    md, page = tmp_path / "summary.md", tmp_path / "out" / "summary.html"
    args = ["report", "summary", "--stats", str(stats), "--dataset", "lab"]
    assert main([*args, "--out-md", str(md), "--out-html", str(page)]) == 0
    # The expected text: apa.result's doctest for this row, and no within-subjects row.
    expected = "ANOVA: F(2, 9) = 41.19, p < .001, ηp² = .90 | no such test in stats.csv"
    assert expected in md.read_text(encoding="utf-8")
    assert "<td>ANOVA: F(2, 9) = 41.19, p &lt; .001" in page.read_text(encoding="utf-8")
    table = tmp_path / "trials.html"
    assert main(["report", "table", str(stats), "--out", str(table)]) == 0
    first = table.read_bytes()
    assert "1 row(s) of" in first.decode("utf-8")
    assert main(["report", "table", str(stats), "--out", str(table)]) == 0
    assert table.read_bytes() == first  # same input, same bytes
    assert "casa report" in capsys.readouterr().out


def test_cli_bad_stats_csv_names_the_missing_columns(tmp_path, capsys):
    stats = tmp_path / "stats.csv"
    stats.write_text("hypothesis,analysis\nH1,anova\n", encoding="utf-8")
    args = ["report", "summary", "--stats", str(stats), "--dataset", "lab"]
    status = main([*args, "--out-md", str(tmp_path / "s.md"), "--out-html", str(tmp_path / "s")])
    err = capsys.readouterr().err
    assert status == 2 and "stats table" in err and "task" in err and "Traceback" not in err
    assert not (tmp_path / "s.md").exists()
