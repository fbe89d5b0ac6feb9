"""Machine-tool volumetric error models and their identification (Ch. 3)."""

from .model import (
    Group,
    JointSpec,
    Machine,
    ModelStructure,
    ShapeSpec,
    halton,
    load_machine,
    parse_machine,
)

__all__: list[str] = [
    "Machine",
    "JointSpec",
    "ShapeSpec",
    "Group",
    "ModelStructure",
    "load_machine",
    "parse_machine",
    "halton",
]
