"""Tags: codes that decode, poses against OpenCV's own projection, and the simulated
camera's reading of a card against the simulator's truth."""

import math

import cv2
import numpy as np
import pytest

from abcwc.experiments.tag_sweep import sweep_tag_views
from abcwc.perception.camera import PinholeCamera
from abcwc.perception.tags import (
    MIN_POSE_SIDE_PX,
    FollowCard,
    aruco_marker_image,
    camera_matrix,
    detect_aruco_markers,
    detect_qr_codes,
    qr_code_image,
    qr_modules,
    square_pose,
)

CAMERA = PinholeCamera.from_fov(640, 480, 57.0, 43.0)


def test_a_qr_code_decodes_to_its_text_with_its_quiet_zone():
    image = qr_code_image("follow ana", module_px=6)
    assert qr_modules("follow ana") == 21  # version 1
    assert image.shape == ((21 + 8) * 6,) * 2
    assert (image[:24] == 255).all()  # four modules of white round the code
    found = detect_qr_codes(np.pad(image, 40, constant_values=255))
    assert [c.text for c in found] == ["follow ana"]


def test_a_marker_is_found_with_its_id_and_corners():
    image = np.pad(aruco_marker_image(12, cell_px=20), 50, constant_values=255)
    (found,) = detect_aruco_markers(image)
    assert found.marker_id == 12
    # the black square spans 6 cells from one cell in: 50 + 20 to 50 + 140 px
    expected = np.array([[70, 70], [190, 70], [190, 190], [70, 190]]) - 0.5
    assert np.abs(found.corners - expected).max() < 0.2


@pytest.mark.parametrize("rotation, position", [
    ((0.0, 0.0, 0.0), (0.0, 0.0, 1.5)),  # face on: where IPPE can flip
    ((0.0, math.pi, 0.0), (0.0, 0.0, 1.5)),  # face on, as a tag facing the camera is
    ((0.3, 2.6, 0.1), (0.4, -0.1, 3.0)),
    ((-0.2, -2.9, 0.0), (-0.8, 0.2, 2.2)),
])
def test_square_pose_recovers_the_pose_opencv_projected(rotation, position):
    side = 0.2
    h = side / 2
    model = np.array([[-h, h, 0], [h, h, 0], [h, -h, 0], [-h, -h, 0]], dtype=np.float64)
    rvec, tvec = np.array(rotation, float), np.array(position, float)
    corners, _ = cv2.projectPoints(model, rvec, tvec, camera_matrix(CAMERA), None)
    pose = square_pose(corners.reshape(4, 2), side, CAMERA)
    assert np.allclose(pose.position, tvec, atol=1e-6)
    assert np.allclose(pose.rotation, cv2.Rodrigues(rvec)[0], atol=1e-6)
    assert pose.range == pytest.approx(math.hypot(tvec[0], tvec[2]))
    assert pose.bearing == pytest.approx(math.atan2(-tvec[0], tvec[2]), abs=1e-9)
    assert pose.reprojection_px < 1e-6


def test_square_pose_and_cards_refuse_what_cannot_be():
    corners = np.array([[300, 200], [340, 200], [340, 240], [300, 240]], float)
    with pytest.raises(ValueError, match="side"):
        square_pose(corners, 0.0, CAMERA)
    with pytest.raises(ValueError, match="finite"):
        square_pose(np.full((4, 2), np.nan), 0.2, CAMERA)
    with pytest.raises(ValueError, match="marker_id"):
        FollowCard("ana", 50)
    with pytest.raises(ValueError, match="non-empty"):
        FollowCard("", 7)
    with pytest.raises(ValueError, match="side"):
        FollowCard("ana", 7, side=-0.2)


def test_a_card_is_a_code_above_a_marker_on_its_middle_line():
    card = FollowCard("ana", 7, side=0.2)
    image = card.image(px_per_m=1000)
    assert image.shape[0] == pytest.approx(card.height * 1000, rel=0.02)
    assert image.shape[1] == pytest.approx(card.width * 1000, rel=0.02)
    assert card.height == pytest.approx(card.marker_width + card.qr_width)
    found = detect_aruco_markers(image)
    assert [m.marker_id for m in found] == [7]
    # drawn to scale: the marker's black square is side / width of the card's width
    assert found[0].side_px / image.shape[1] == pytest.approx(card.side / card.width,
                                                               rel=0.01)
    # on the card's middle line, marker_drop below its centre (image rows run down)
    assert found[0].centre[0] / image.shape[1] == pytest.approx(0.5, abs=0.005)
    assert found[0].centre[1] / image.shape[0] == pytest.approx(
        0.5 + card.marker_drop / card.height, abs=0.005)
    codes = detect_qr_codes(image)
    assert [c.text for c in codes] == ["ana"]
    assert codes[0].centre[1] < found[0].centre[1]  # the code above the marker


@pytest.fixture(scope="module")
def sweep():
    return sweep_tag_views(count=120, seed=11)


def test_the_marker_s_range_and_bearing_from_the_simulated_camera(sweep):
    """The issue's bar: range within 3 % and bearing within 1 degree wherever the tag
    is read for its pose (a marker of MIN_POSE_SIDE_PX or more across; the worst, 2.5 %,
    is a marker 20 px across at 6 m)."""
    ranged = sweep.side_px >= MIN_POSE_SIDE_PX
    assert ranged.sum() > 40
    assert np.abs(sweep.range_error[ranged]).max() < 0.03
    assert abs(np.mean(sweep.range_error[ranged])) < 0.005  # no bias left
    assert np.abs(sweep.bearing_error[sweep.found]).max() < math.radians(0.1)
    assert sweep.farthest(ranged) > 5.5  # m: the range is good to 5.5 m and more


def test_each_tag_s_reading_range(sweep):
    """Measured, not assumed: a 0.2 m marker is found out to nearly 9 m; its QR code
    (21 modules of 9.5 mm, about 4 px each at 1.4 m, 2.8 px at 2 m) reads to 1.0-2.1 m
    (here once at 2.0 m, mostly within 1.4 m), and to 1.8-2.4 m on the image enlarged
    twice."""
    assert sweep.farthest(sweep.found) > 8.0
    assert 1.0 <= sweep.farthest(sweep.qr) <= 2.1
    assert 1.8 <= sweep.farthest(sweep.qr_upscaled) <= 2.4
    assert not sweep.qr[sweep.distance > 2.2].any()
    assert sweep.found[sweep.distance < 6.0].mean() > 0.85  # failures: half out of view
