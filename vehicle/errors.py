"""The vehicle model's exceptions (no exudyn import: the application layer catches them without
loading the multibody engine)."""
from pneumorail.errors import PneumorailError


class Derailed(PneumorailError, RuntimeError):
    """A wheelset left its rails (contact guidance: it ran off the contact table): the car
    derailed, a state the model does not continue from."""
