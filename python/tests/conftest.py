import os
import random
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))  # oracle.py

import vkas  # noqa: E402


@pytest.fixture
def seed(request):
    """A random seed, printed (pytest shows it with a failure); VKAS_TEST_SEED=n replays one."""
    value = int(os.environ.get("VKAS_TEST_SEED", random.randrange(2**32)))
    print(f"{request.node.name}: seed {value} (VKAS_TEST_SEED={value} replays it)")
    return value


@pytest.fixture
def rng(seed):
    return np.random.default_rng(seed)


@pytest.fixture(scope="session")
def dev():
    return vkas.Device(validation=True, threads=0)


@pytest.fixture(scope="session")
def dev_novalidation():
    return vkas.Device(validation=False, threads=0)


def pytest_report_header(config):
    return f"vkas {vkas.__version__} from {os.path.dirname(vkas.__file__)}"
