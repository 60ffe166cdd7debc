"""The resolution study from Python: the same files as `inimtrace resolution`, byte for byte, and
its tables as records."""

import inimtrace
import pytest

from conftest import ROOT, load_json

TINY = ROOT / "studies" / "tiny.toml"
TABLES = ["mtf.csv", "mtf50.csv", "accommodation.csv", "display.json", "display.md"]


def test_resolution_writes_the_clis_files_and_returns_them_as_records(cli, tmp_path):
    cli("resolution", TINY, "--out", tmp_path / "cli")
    r = inimtrace.resolution(TINY, tmp_path / "py", threads=2)
    assert r.out == str(tmp_path / "py")
    for name in TABLES:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    # study.json: every setting equal (timings differ from run to run, the version string between builds).
    py, cl = (load_json(tmp_path / d / "study.json") for d in ("py", "cli"))
    for k in ("timings", "total_seconds", "inimtrace_version"):
        py.pop(k), cl.pop(k)
    assert py == cl
    # The records are the CSV rows, numbers as floats.
    assert r.mtf and set(r.mtf[0]) >= {"source", "target_diopters", "focus_diopters", "frequency_cpd", "contrast"}
    assert all(isinstance(row["contrast"], float) for row in r.mtf)
    assert len(r.mtf) == sum(1 for _ in open(tmp_path / "cli" / "mtf.csv")) - 1
    assert {row["source"] for row in r.accommodation} >= {"ground_truth"}
    # Every row carries its precision: the 95% half-width, samples per pixel and replicates.
    for table, ci95 in ((r.mtf, "contrast_ci95"), (r.mtf50, "mtf50_ci95"), (r.accommodation, "contrast_at_peak_ci95")):
        assert all({ci95, "samples_per_pixel", "replicates"} <= set(row) for row in table), table[0]
        assert all(row["samples_per_pixel"] == 12 and row["replicates"] == 3 for row in table)  # 4 x 3 replicates
        assert all(type(row["samples_per_pixel"]) is int and type(row["replicates"]) is int for row in table)
    assert all(row["contrast_at_peak_ci95"] > 0 for row in r.accommodation)
    assert r.display == load_json(tmp_path / "cli" / "display.json")
    assert r.timings and all(t["seconds"] >= 0 for t in r.timings)


def test_resolution_errors_name_the_file(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\npupil_diameter_mm = "wide"\n')
    with pytest.raises(inimtrace.ConfigError) as e:
        inimtrace.resolution(bad, tmp_path / "out")
    assert "bad.toml" in str(e.value)
