"""Find a known sign with the camera and turn to face it (the thesis's 4.1.8: the exit
sign "identified from all locations inside the lab", with a servo that swept the camera
until the object was seen; here the chair turns instead).

:class:`SignSeeker` runs three phases:

1. **Looking**: turn on the spot at ``turn_rate`` and run the detector on every new
   camera image. The chair's heading comes from the gyro (integrated here, rad), so the
   behaviour knows when it has turned all the way round.
2. **Facing**: a verified detection gives the sign's bearing in the image. The image
   is up to a frame old when it is read, so the sign's direction is kept in the gyro's
   heading (``sign = heading_at_image + bearing_image``; ``bearing_now = sign -
   heading_now``) and the chair turns ``gain * bearing_now`` (limited to
   ``turn_rate``) until the sign's bearing is within ``tolerance`` on a fresh image,
   then stops: succeeded.
3. **Moving on**: after a full turn without a verified sighting the sign is hidden from
   here (a shelf, a table): with a ``navigator`` and ``vantage`` places the chair drives
   to the next one and looks again; without, or after the last, it fails and says so.
"""

from __future__ import annotations

import math

from abcwc.behaviours.base import BehaviourBase, positive_number
from abcwc.geometry import wrap_angle
from abcwc.perception.known_objects import Detection, ObjectDetector
from abcwc.types import CAMERA_FRAME, CameraImage, SensorFrame, Twist


class SignSeeker(BehaviourBase):
    """Turn until ``detector`` finds ``name`` (verified), then face it (module notes).
    ``navigator`` (a :class:`~abcwc.behaviours.navigator.Navigator`) and ``vantage``
    (place names or poses it can go to) let it look again from elsewhere."""

    def __init__(self, detector: ObjectDetector, name: str, turn_rate: float = 0.4,
                 gain: float = 1.5, tolerance: float = math.radians(2.0),
                 patience: float = 2.0, navigator: object | None = None,
                 vantage: tuple = ()):
        super().__init__()  # every frame: the navigator, when driving, needs each one
        if name not in [obj.name for obj in detector.objects]:
            raise ValueError(f"the detector does not look for {name!r}; it knows "
                             f"{', '.join(obj.name for obj in detector.objects)}")
        self.detector, self.name = detector, name
        self.turn_rate = positive_number("turn_rate", turn_rate, "rad/s")
        self.gain = positive_number("gain", gain, "1/s")
        self.tolerance = positive_number("tolerance", tolerance, "rad")
        self.patience = positive_number("patience", patience, "s")
        if vantage and navigator is None:
            raise ValueError("vantage places need a navigator to drive to them")
        self.navigator, self.vantage = navigator, tuple(vantage)
        self.reset()

    def reset(self) -> None:
        super().reset()
        self.phase = "looking"
        self.heading = 0.0  # rad, integrated gyro since the start
        self.last_seen: Detection | None = None
        self.sightings = 0
        self.images = 0
        self._gyro_t: float | None = None
        self._turned = 0.0  # rad turned while looking from this spot
        self._image_t = -math.inf
        self._headings: list[tuple[float, float]] = []  # (t, heading) over the last second
        self._sign: float | None = None  # rad: the sign's direction in the gyro's heading
        self._fresh = False  # the last image showed the sign
        self._seen_t = -math.inf  # s: the last verified sighting's image
        self._next_vantage = 0

    @property
    def bearing(self) -> float | None:
        """rad (left positive) from the chair's heading now to the sign, as last seen."""
        return None if self._sign is None else wrap_angle(self._sign - self.heading)

    def observe(self, frame: SensorFrame) -> None:
        if self._gyro_t is not None and math.isfinite(frame.gyro_z):
            turn = frame.gyro_z * (frame.t - self._gyro_t)
            self.heading += turn
            if self.phase == "looking":
                self._turned += abs(turn)
        self._gyro_t = frame.t
        self._headings = [(t, h) for t, h in self._headings if frame.t - t < 1.0]
        self._headings.append((frame.t, self.heading))

    def update(self, frame: SensorFrame) -> Twist:
        image = frame.readings.get(CAMERA_FRAME)
        if isinstance(image, CameraImage) and image.stamp > self._image_t:
            self._image_t = image.stamp
            if self.phase != "moving on":
                self._look(image)
        if self.phase == "moving on":
            return self._move_on(frame)
        bearing = self.bearing
        if self.phase == "facing" and frame.t - self._seen_t > self.patience:
            self.phase, self._sign = "looking", None  # not seen again: look on
        elif self.phase == "facing" and bearing is not None:
            if abs(bearing) <= self.tolerance and self._fresh:
                self.succeed()
                return Twist(0.0, 0.0)
            return Twist(0.0, max(-self.turn_rate, min(self.turn_rate, self.gain * bearing)))
        if self._turned >= math.tau:
            return self._hidden_from_here()
        return Twist(0.0, self.turn_rate)

    def _look(self, image: CameraImage) -> None:
        """Run the detector on ``image``; a verified sighting fixes the sign's direction
        (a missed frame while facing keeps the last one)."""
        self.images += 1
        found = [d for d in self.detector.detect(image) if d.name == self.name]
        self._fresh = bool(found)
        if not found:
            return
        self.last_seen, self.sightings = found[0], self.sightings + 1
        self._seen_t = image.stamp
        then = min(self._headings, key=lambda th: abs(th[0] - image.stamp),
                   default=(0.0, self.heading))[1]
        self._sign = then + found[0].bearing
        self.phase = "facing"

    def _hidden_from_here(self) -> Twist:
        if self._next_vantage >= len(self.vantage):
            where = "from here" if not self.vantage else "from any vantage place"
            self.fail(f"no verified {self.name!r} sign in a full turn {where}")
            return Twist(0.0, 0.0)
        self.navigator.go_to(self.vantage[self._next_vantage])  # type: ignore[union-attr]
        self._next_vantage += 1
        self.phase = "moving on"
        return Twist(0.0, 0.0)

    def _move_on(self, frame: SensorFrame) -> Twist:
        command = self.navigator(frame)  # type: ignore[misc]
        if self.navigator.running:  # type: ignore[union-attr]
            return command
        if self.navigator.failure is not None:  # type: ignore[union-attr]
            self.fail(f"could not reach a vantage place: {self.navigator.failure}")
            return Twist(0.0, 0.0)
        self.phase, self._turned, self._sign = "looking", 0.0, None
        return Twist(0.0, 0.0)


__all__ = ["SignSeeker"]
