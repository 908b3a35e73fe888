"""Contact history: the values a contact carries from step to step, owned by the effects that
keep them, and one way to load, store and clear them for every kind of contact.

An effect declares its history values in ``contact_fields`` as ``"<value>_history"`` (a
vector per contact, in m or rad: Hertz-Mindlin's ``tangential_history``, the spring of its
tangential displacement; EPSD rolling's ``rolling_history``, its rolling spring), as LIGGGHTS's
``add_history_value`` or DEM-Engine's per-contact wildcards. ``History`` is the struct of the
enabled effects' values, and nothing else (a scene without EPSD carries no rolling spring).

Each value is zero while its contact is open: cleared when the contact opens (or is only
near, within a heat margin, without touching), and a new contact starts from zero; a contact
that moves on to a neighbouring triangle of the same body takes the values of the one it left
(``take``). Where the values live is the caller's: per neighbour entry (pairs), per particle
and plane wall, per mesh contact; ``make_history_io`` binds the same load, store and clear to
each storage.
"""
import taichi as ti

SUFFIX = "_history"


def history_members(effects) -> tuple[str, ...]:
    """The history values the enabled contact effects keep, in effect order (``tangential``,
    ``rolling``, ...)."""
    out: list[str] = []
    for e in effects:
        if e.stage != "contact":
            continue
        for name, (is_vector, _) in e.contact_fields.items():
            assert name.endswith(SUFFIX) and is_vector, f"{e.name}: {name}"
            member = name[: -len(SUFFIX)]
            if member not in out:
                out.append(member)
    return tuple(out)


def make_history_type(real, members: tuple[str, ...]):
    """The ``History`` struct of ``members``, each a 3-vector in the simulation's precision."""
    vec3 = ti.types.vector(3, real)
    return ti.types.struct(**{m: vec3 for m in members})


class HistoryIO:
    """ti.funcs over one storage of the history values (``fields``: member -> field, indexed
    by a neighbour entry, a (particle, wall) vector or a mesh entry):

    ``empty()``          all values zero (a new contact, or a contact with no history)
    ``load(I)``          the values stored at I
    ``store(I, h)``      write h at I
    ``clear(I)``         zero the values at I (the contact opened)
    ``take(I, J)``       the values at J, zeroing them there (a contact moving from J to I)
    """

    def __init__(self, History, members: tuple[str, ...], fields: dict):
        names = tuple(members)
        storage = tuple(fields[m] for m in names)
        zero = [0.0, 0.0, 0.0]

        @ti.func
        def empty():
            return History(**{names[q]: ti.Vector(zero) for q in ti.static(range(len(names)))})

        @ti.func
        def load(index):
            return History(**{names[q]: storage[q][index] for q in ti.static(range(len(names)))})

        @ti.func
        def store(index, h):
            for q in ti.static(range(len(names))):
                storage[q][index] = h[names[q]]     # the member of that name

        @ti.func
        def clear(index):
            for q in ti.static(range(len(names))):
                storage[q][index] = ti.Vector(zero)

        @ti.func
        def take(index, source):
            h = load(source)
            clear(source)
            return h

        self.empty, self.load, self.store, self.clear, self.take = empty, load, store, clear, take


def make_history_io(History, members: tuple[str, ...], fields: dict) -> HistoryIO:
    """The load, store and clear of the history values held in ``fields`` (member -> field)."""
    missing = [m for m in members if fields.get(m) is None]
    assert not missing, f"no storage for the history values {missing}"
    return HistoryIO(History, members, fields)
