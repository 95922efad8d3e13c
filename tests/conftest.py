"""Shared test configuration: ``--runslow`` runs the tests marked ``slow`` (CI does)."""
import pytest


def pytest_addoption(parser):
    parser.addoption("--runslow", action="store_true", default=False,
                     help="also run tests marked slow (the README's test command does)")


def pytest_collection_modifyitems(config, items):
    if config.getoption("--runslow"):
        return
    skip = pytest.mark.skip(reason="slow: run with --runslow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


def pytest_configure(config):
    # The suite runs the driver's core as plain Python (no compile time); the
    # numba engine is compared with it in tests/test_backends.py.
    import os

    os.environ.setdefault("SYMVIB_BACKEND", "python")
    # The suite's own processes and children (the CLI in a subprocess imports the installed package,
    # whose engines compiled at install time would decide where today's compile does) keep today's
    # behaviour; tests/test_installed_engines.py switches them on where it tests them.
    os.environ.setdefault("SYMVIB_INSTALLED_ENGINES", "off")
