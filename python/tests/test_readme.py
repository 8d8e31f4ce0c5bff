"""The README's Python example, run as written, prints what its comments say."""

import contextlib
import io
import re

from conftest import REPO


def test_readme_example_prints_what_the_readme_says():
    text = (REPO / "README.md").read_text()
    section = text[text.index("## From Python") :]
    code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
    # each `print(...)  # expected` line: what it prints, before any "  (remark)"
    expected = [m.group(1).split("  (")[0].strip() for m in re.finditer(r"^print\(.*?\)\s+# (.*)$", code, re.M)]
    assert len(expected) >= 2, code
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), {})
    assert out.getvalue().splitlines() == expected
