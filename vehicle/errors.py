"""The vehicle model's exceptions (no exudyn import: the application layer catches them without
loading the multibody engine)."""
from pneumorail.errors import PneumorailError


class Derailed(PneumorailError, RuntimeError):
    """A wheelset left its rails (contact guidance: it ran off the contact table): the car
    derailed, a state the model does not continue from."""


class WheelSlide(PneumorailError, RuntimeError):
    """A wheelset driven or braked through its wheels (``drive``) slides: its traction or braking
    asked for more than the adhesion, and its longitudinal creepage ran past
    :data:`vehicle.car.wheel_drive.SLIDE_CREEPAGE`. The model has no wheel-slide protection: it
    does not continue from there."""
