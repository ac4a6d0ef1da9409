"""``crankbench report --bench`` appends the speed-against-error tables and plots."""

import re

from crankbench.analysis.bench import Row
from crankbench.analysis.commands.report import add_bench_appendix
from crankbench.analysis.report import Report


def test_bench_appendix_has_a_table_and_a_plot_per_suite_and_states_failures(tmp_path):
    rows = [Row("torsion", "dqds", "n=10", 1e-16, "max rel", "closed form", 1e-4, bound=1e-13),
            Row("torsion", "eigh", "n=10", 7e-16, "max rel", "closed form", 2e-4),
            Row("orders", "cot", "64 rev", 0.02, "rms rel", "synthesis", 3e-2, bound=0.005)]
    rep = Report(title="t")
    add_bench_appendix(rep, rows)
    assert rep.sections == ["Appendix: speed against error"]
    assert rep.n_figures == 2
    html = (tmp_path / "r.html")
    rep.save(html)
    text = html.read_text()
    assert "3 rows from `crankbench bench --quick`" in text
    assert "1 row(s) exceed their documented bound." in text
    assert len(re.findall(r"bench: (torsion|orders)</", text)) >= 2
