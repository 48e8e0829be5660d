"""The README's and the guide's Python examples run as written."""
import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parent.parent
README, GUIDE = ROOT / "README.md", ROOT / "docs" / "guide.md"


def python_blocks(path):
    return re.findall(r"```python\n(.*?)```", path.read_text(), re.S)


def test_readme_quick_start_fits_and_tracks_the_target(capsys):
    blocks = python_blocks(README)
    assert len(blocks) == 1
    lines = [line for line in blocks[0].splitlines() if line.strip()]
    assert len(lines) <= 25  # the quick start stays short
    exec(compile(blocks[0], str(README), "exec"), {"__name__": "readme"})
    assert "1 track at [[600.0, 300.0]]" in capsys.readouterr().out


def test_guide_examples_run(capsys):
    blocks = python_blocks(GUIDE)
    assert len(blocks) >= 2
    for block in blocks:
        exec(compile(block, str(GUIDE), "exec"), {"__name__": "guide"})
    printed = capsys.readouterr().out
    assert "[0.4 0. ]" in printed
    assert "[0.9 0.  0.9 0.  0.9]" in printed  # 3-D coverage: horizon at height, the beam
    assert "[0.9 0.  0. ]\n[0.9 0.9 0.9]" in printed  # the MTI notch, then a moving radar
    assert "ahead 0.090, behind 9.5e-05" in printed  # the learned clutter map
    assert "True 120.0\n[ True False False]" in printed  # a radar on Southsea's shore
    # pooled: the rings' level, and with the weight estimated no scatter of its cells
    assert "ring, weight 10: far λ 9.9e-03 ± 7e-03" in printed
    assert "ring, weight estimated: far λ 9.7e-03 ± 2e-03" in printed
    found = re.search(r"GM-PHD: \d+ components, (\d+) tracks", printed)
    assert found and int(found.group(1)) > 0
    found = re.search(r"JPDA: (\d+) tracks", printed)
    assert found and int(found.group(1)) > 0
