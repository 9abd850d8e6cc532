"""Element names as the user wrote them, from the labels the reader makes
(mbseig.casefile.fields.expand: ``section[k] repr(name)``); the reference is the name in the
case text itself (exact string equality)."""

from mbseig.casefile.fields import expand
from mbseig.numerics import element_name, user_names


def test_labels_of_the_reader_give_back_the_names():
    items = [{"name": "actuator"}, {"name": "finger's tip"}, {"name": 'say "hi"'}, {}]
    labels = [label for _, label, _ in expand("forces", items, {})]
    assert [element_name(x) for x in labels] == ["actuator", "finger's tip", 'say "hi"',
                                                 "forces[3]"]
    part = labels[0] + " (rigid length)"
    assert element_name(part) == "actuator (rigid length)"
    assert element_name(part, part=False) == "actuator"
    assert user_names(f"{labels[0]} pulls {labels[1]}") == "actuator pulls finger's tip"
    assert element_name("gravity") == "gravity"
