"""One row of "Stability where methods fail": the naive method and its answer, mbseig's answer,
the reference that decides, and whether each is right."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class FailCase:
    name: str
    naive_method: str
    naive: str  # the naive method's answer
    mbseig: str  # mbseig's answer
    reference: str  # the truth and its source
    naive_wrong: bool
    mbseig_right: bool
    data: dict = field(default_factory=dict)
