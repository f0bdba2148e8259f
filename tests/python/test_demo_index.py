"""scripts/demo-index: the demo's one page (issue 44)."""
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def test_a_section_per_step_plots_shown_and_files_linked(tmp_path):
    for rel, data in [("drive45/ode/path.png", b"\x89PNG"), ("drive45/ode/trajectory.csv", b"t\n"),
                      ("rrr_writing_ilc/report.html", b"<html></html>"), ("stray/extra.csv", b"t\n")]:
        path = tmp_path / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    done = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "demo-index"), str(tmp_path)],
                          capture_output=True, text=True, check=True)
    assert done.stdout.strip() == str(tmp_path / "index.html")
    page = (tmp_path / "index.html").read_text()
    assert "<h2 id=\"Five scenes on three engines\">" in page
    assert "<img src=\"drive45/ode/path.png\"" in page
    assert "<a href=\"drive45/ode/trajectory.csv\">" in page
    assert "Reports: <a href=\"rrr_writing_ilc/report.html\">" in page
    # What no step names comes last; steps with no files are left out.
    assert page.index("Other files") > page.index("Iterative learning control")
    assert "<a href=\"stray/extra.csv\">" in page
    assert "Learning to drive" not in page
    assert not (tmp_path / "index.html.tmp").exists()


def test_a_missing_folder_is_exit_2(tmp_path):
    done = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "demo-index"), str(tmp_path / "none")],
                          capture_output=True, text=True)
    assert done.returncode == 2
    assert "is not a folder" in done.stderr
