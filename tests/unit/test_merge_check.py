"""What LeRobot's aggregation requires to match, said before LeRobot is asked (`langgap merge-lerobot`)."""

from __future__ import annotations

import json

import pytest

from langgap.demos.export import FPS, features
from langgap.demos.merge import incompatibilities, merge_lerobot_datasets
from langgap.errors import LangGapError


def _dataset(root, **changes):
    info = {"fps": FPS, "robot_type": "panda", "features": features(64), **changes}
    (root / "meta").mkdir(parents=True)
    (root / "meta" / "info.json").write_text(json.dumps(info))
    return root


def test_datasets_of_one_label_robot_and_schema_are_compatible_whatever_their_encoding(tmp_path):
    encoded = features(64)
    encoded["observation.images.image"]["info"] = {"video.codec": "h264"}
    roots = [_dataset(tmp_path / "a"), _dataset(tmp_path / "b", features=encoded)]
    assert incompatibilities(roots) == []


@pytest.mark.parametrize(
    ("change", "named"),
    [
        ({"fps": 20}, "fps 20, not 10"),
        ({"robot_type": "libero"}, "robot_type 'libero'"),
        ({"features": features(256)}, "feature observation.images.image is"),
        (
            {"features": {k: v for k, v in features(64).items() if k != "observation.images.image2"}},
            "image2 is in only",
        ),
    ],
)
def test_each_difference_lerobot_refuses_is_named(tmp_path, change, named):
    roots = [_dataset(tmp_path / "ours"), _dataset(tmp_path / "theirs", **change)]
    problems = incompatibilities(roots)
    assert problems and all(p.startswith(str(roots[1])) for p in problems) and named in problems[0]


def test_merge_refuses_before_writing(tmp_path):
    roots = [_dataset(tmp_path / "ours"), _dataset(tmp_path / "theirs", fps=20)]
    with pytest.raises(LangGapError, match="cannot aggregate these datasets: .*fps 20, not 10"):
        merge_lerobot_datasets(roots, tmp_path / "merged")
    assert not (tmp_path / "merged").exists()
