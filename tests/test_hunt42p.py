"""A parameter the classifier cannot use is a ValueError, as scikit-learn's estimators refuse
one (its users write ``except ValueError``), and still the ConfigError the command line
prints as one line: at fit, at ``describe_plan`` and, for the vote's parameters, at predict.
(They were ConfigError alone: ``except ValueError`` let ``k=0`` through.)"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from cbr.estimator import CaseBaseClassifier
from features.errors import ConfigError
from tests.test_cbr_clips import arm_dataset

# each parameter, a value it cannot take, and the name the refusal gives
BAD: list[tuple[dict[str, Any], str]] = [
    ({"k": 0}, "k"),
    ({"weights": "x"}, "weights"),
    ({"trim": 2.0}, "trim"),
    ({"mirror": "sideways"}, "mirror"),
    ({"phases": -1}, "phases"),
    ({"similarity": "cosine"}, "similarity"),  # the registry's own check
    ({"features": "pixels"}, "features"),  # the feature configuration's own check
    ({"length": 0}, "length"),
    ({"similarity": "dtw", "similarity_params": {"band": -1}}, "band"),
    ({"trim": 0.5, "editor": "cnn"}, "trim"),
]


# on one xdist worker: the module's data made once, not once per worker
pytestmark = pytest.mark.xdist_group("hunt42p")


@pytest.fixture(scope="module")
def data() -> tuple[list[Any], np.ndarray]:
    return arm_dataset(4, seed=1)


@pytest.mark.parametrize(("params", "named"), BAD, ids=[n for _, n in BAD])
def test_a_parameter_it_cannot_use_is_a_value_error_at_fit(
    params: dict[str, Any], named: str, data: tuple[list[Any], np.ndarray]
) -> None:
    X, y = data
    with pytest.raises(ValueError, match=named) as caught:
        CaseBaseClassifier(**params).fit(X, y)
    assert isinstance(caught.value, ConfigError)
    with pytest.raises(ValueError, match=named):
        CaseBaseClassifier(**params).describe_plan()


def test_a_vote_parameter_set_after_fit_is_a_value_error_at_predict(
    data: tuple[list[Any], np.ndarray],
) -> None:
    X, y = data
    clf = CaseBaseClassifier().fit(X, y)
    clf.set_params(k=0)
    with pytest.raises(ValueError, match="k: must be a positive integer"):
        clf.predict(X[:1])
