"""The Python tests' files: pytest's temporary directories (tmp_path) are removed after a run in
which every test passed, and kept (pytest prints where) after a failure, as the C++ tests keep
theirs (tests/support/scratch.h)."""
import shutil

import pytest


@pytest.fixture(scope="session", autouse=True)
def remove_files_after_a_passing_run(request, tmp_path_factory):
    yield
    if request.session.testsfailed == 0:
        base = tmp_path_factory.getbasetemp()
        shutil.rmtree(base, ignore_errors=True)
        # pytest's per-user folder, when it holds nothing else than its link to the run just removed
        parent = base.parent
        if parent.name.startswith("pytest-of-"):
            current = parent / "pytest-current"
            if current.is_symlink() and not current.exists():
                current.unlink()
            try:
                parent.rmdir()
            except OSError:
                pass  # other runs' folders: theirs to remove
