"""nhdyn.from_sympy: a model from SymPy expressions (sympy.physics.mechanics dynamicsymbols
included), written as the text of a model file (docs/model-format.md) and loaded as any other, so
that a SymPy user's T, V, coordinates and constraints run without rewriting them.

Each expression is printed in the model file's syntax: a coordinate q(t) becomes its name, its
derivatives q' and q''; SymPy's ** becomes ^, Abs abs, E exp(1); every other symbol must be a
parameter (given a value in `parameters`) or the time. A symbol that fits none of these is refused,
naming it and what it could have been.

nhdyn.from_sympy_mechanics takes sympy.physics.mechanics' own description (frames, bodies,
generalized speeds and their kinematic differential equations, a KanesMethod) and writes it in q
and q' for from_sympy: nhdyn's equations are in the coordinates' velocities, so the speeds are
solved for from the kinematic differential equations and replaced.
"""

import json


def _sympy():
    try:
        import sympy
    except ImportError as error:  # pragma: no cover - Debian: apt-get install python3-sympy
        raise ImportError("nhdyn.from_sympy needs SymPy (apt-get install python3-sympy)") from error
    return sympy


def _name(obj):
    """The name of a coordinate given as a Symbol or a dynamicsymbol q(t)."""
    sympy = _sympy()
    if isinstance(obj, sympy.Symbol):
        return obj.name
    if isinstance(obj, sympy.core.function.AppliedUndef):
        return type(obj).__name__
    raise _input_error("coordinate {!r}: give a Symbol or a dynamicsymbol such as q(t)".format(obj))


def _input_error(message):
    from . import InputError

    return InputError("from_sympy: " + message)


class _Translator:
    """Prints SymPy expressions in the model file's syntax, knowing the coordinates, their
    velocities, the parameters and the time."""

    def __init__(self, q, qd, parameters, t):
        sympy = _sympy()
        self.sympy = sympy
        self.t = t if t is not None else sympy.Symbol("t")
        self.names = [_name(c) for c in q]
        self.replace = {}
        for c, name in zip(q, self.names):
            self.replace[c] = sympy.Symbol(name)
            if isinstance(c, sympy.core.function.AppliedUndef):
                self.replace[c.diff(self.t)] = sympy.Symbol(name + "'")
                self.replace[c.diff(self.t, 2)] = sympy.Symbol(name + "''")
        if qd is not None:
            if len(qd) != len(q):
                raise _input_error("qd: {} velocities for {} coordinates".format(len(qd), len(q)))
            for v, name in zip(qd, self.names):
                self.replace[v] = sympy.Symbol(name + "'")
        self.parameters = {(p.name if isinstance(p, sympy.Symbol) else str(p)): p for p in parameters}
        self.known = set(self.names) | {n + "'" for n in self.names} | set(self.parameters) | {self.t.name}

    def __call__(self, expression, what, accelerations=False, extra=()):
        sympy = self.sympy
        try:
            e = sympy.sympify(expression)
        except (sympy.SympifyError, TypeError) as error:
            raise _input_error("{}: {!r} is not a SymPy expression ({})".format(what, expression, error)) from None
        for d in e.atoms(sympy.Derivative):
            if d not in self.replace:
                raise _input_error("{}: {} is a derivative that is not a coordinate's velocity{}".format(
                    what, d, " or acceleration" if accelerations else ""))
        # Accelerations, then velocities (q(t).diff(t) contains q(t)), then the coordinates.
        derivatives = [(k, v) for k, v in self.replace.items() if isinstance(k, sympy.Derivative)]
        derivatives.sort(key=lambda item: -item[0].derivative_count)
        e = e.subs(derivatives)
        e = e.xreplace({k: v for k, v in self.replace.items() if not isinstance(k, sympy.Derivative)})
        for f in e.atoms(sympy.core.function.AppliedUndef):
            raise _input_error("{}: {} is a function of time that is not a coordinate; the coordinates are {}".format(
                what, f, ", ".join(self.names)))
        allowed = self.known | ({n + "''" for n in self.names} if accelerations else set()) | set(extra)
        for s in sorted(e.free_symbols, key=lambda s: s.name):
            if not accelerations and s.name.endswith("''") and s.name[:-2] in self.names:
                raise _input_error("{}: the acceleration {} has no place here (T, V, forces, actuators and position "
                                   "or velocity constraints depend on t, q and q' only)".format(what, s.name))
            if s.name not in allowed:
                raise _input_error(
                    "{}: cannot place the symbol {!r}: it is not a coordinate ({}), a velocity ({}), a parameter "
                    "(give its value in parameters={{{}: ...}}){} or the time {}".format(
                        what, s.name, ", ".join(self.names), ", ".join(n + "'" for n in self.names), s.name,
                        ", an acceleration, a reaction R_x or an output above it" if extra else "",
                        self.t.name))
        # The model file has pi and exp() but no constant e.
        e = e.xreplace({sympy.E: sympy.Symbol("exp(1)")})
        return sympy.sstr(e, order="none").replace("**", "^").replace("Abs(", "abs(")


def _value(value, what, translate=None):
    """A number as TOML; a SymPy constant expression (pi/6) as its text, so it keeps its exact value;
    with `translate`, an expression in the parameters too (an initial value l*sin(theta0))."""
    sympy = _sympy()
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, sympy.Basic):
        if value.free_symbols:
            if translate is None:
                raise _input_error("{}: {} is not a constant (a parameter's value is a number or an expression in "
                                   "numbers and pi)".format(what, value))
            return json.dumps(translate(value, what))
        if not (value.is_Integer or value.is_Float):
            return json.dumps(sympy.sstr(value.xreplace({sympy.E: sympy.Symbol("exp(1)")})).replace("**", "^"))
    try:
        return json.dumps(float(value))
    except (TypeError, ValueError):
        raise _input_error("{}: {!r} is not a number".format(what, value)) from None


def _key(key, what):
    """A name for a table key: a string, or a Symbol's name."""
    sympy = _sympy()
    name = key.name if isinstance(key, sympy.Symbol) else key
    if not isinstance(name, str) or not name:
        raise _input_error("{}: the key {!r} is not a name (give a string)".format(what, key))
    return name


def _reactions(tr):
    return {"R_" + n for n in tr.names}


def _level(text):
    return "acceleration" if "''" in text else "velocity" if "'" in text else "position"


def _actuator(tr, program, actuator):
    """The actuator of a program as its TOML value: a coordinate's name, or the n entries of a
    generalized-force direction."""
    sympy = tr.sympy
    what = "program {}: actuator".format(program)
    if isinstance(actuator, str) or isinstance(actuator, (sympy.Symbol, sympy.core.function.AppliedUndef)):
        if isinstance(actuator, str):
            name = actuator if actuator in tr.names else None
        else:
            image = tr.replace.get(actuator)
            name = image.name if image is not None and image.name in tr.names else None
        if name is None:
            raise _input_error("{} {!r} is not a coordinate ({}); give a coordinate or a generalized-force vector "
                               "of {} expressions".format(what, str(actuator), ", ".join(tr.names), len(tr.names)))
        return json.dumps(name)
    if isinstance(actuator, sympy.MatrixBase):  # a column or a row
        entries = list(actuator) if 1 in actuator.shape else None
    elif isinstance(actuator, (list, tuple)) or getattr(actuator, "ndim", None) == 1:  # numpy too
        entries = list(actuator)
    else:
        entries = None
    if entries is None or len(entries) != len(tr.names):
        raise _input_error("{} {} is neither a coordinate ({}) nor a generalized-force vector of {} entries, one "
                           "per coordinate{}".format(what, str(actuator), ", ".join(tr.names), len(tr.names),
                                                     "" if entries is None else " (it has {})".format(len(entries))))
    return json.dumps([tr(e, "{}[{}]".format(what, i)) for i, e in enumerate(entries)])


def _programs(tr, programs):
    lines = []
    for pname, value in (programs or {}).items():
        pname = _key(pname, "programs")
        if not isinstance(value, (tuple, list)) or len(value) != 2:
            raise _input_error("program {}: give (expression, actuator), not {!r}".format(pname, value))
        expression, actuator = value
        text = tr(expression, "program {}".format(pname), accelerations=True)
        lines += ["\n[[programs]]", "name = {}".format(json.dumps(pname)),
                  "{} = {}".format(_level(text), json.dumps(text)),
                  "actuator = {}".format(_actuator(tr, pname, actuator))]
    return lines


_DIRECTIONS = ("rising", "falling", "both")
_ACTIONS = ("stop", "record")


def _events(tr, events, extra):
    lines = []
    for ename, value in (events or {}).items():
        ename = _key(ename, "events")
        options = dict(value) if isinstance(value, dict) else {"expression": value}
        if "when" in options and "expression" not in options:  # the model file's spelling
            options["expression"] = options.pop("when")
        unknown = sorted(set(options) - {"expression", "direction", "action"})
        if unknown or "expression" not in options:
            raise _input_error("event {}: {}; give an expression or dict(expression=..., direction=..., "
                               "action=...)".format(ename, "unknown key {}".format(", ".join(map(repr, unknown)))
                                                    if unknown else "no expression"))
        text = tr(options["expression"], "event {}".format(ename), accelerations=True, extra=extra)
        lines += ["\n[[events]]", "name = {}".format(json.dumps(ename)), "when = {}".format(json.dumps(text))]
        for key, allowed in (("direction", _DIRECTIONS), ("action", _ACTIONS)):
            if key in options:
                if options[key] not in allowed:
                    raise _input_error("event {}: {} {!r} is not one of {}".format(
                        ename, key, options[key], ", ".join(map(repr, allowed))))
                lines.append("{} = {}".format(key, json.dumps(options[key])))
    return lines


def from_sympy(T, V, q, constraints=(), parameters=None, *, qd=None, forces=None, initial=None, t=None,
               programs=None, events=None, outputs=None, name="sympy_model", simulation=None,
               file_name="<from_sympy>"):
    """A Model from SymPy: kinetic energy T and potential V in the coordinates q (Symbols or
    sympy.physics.mechanics dynamicsymbols q(t); with Symbols, qd lists their velocity Symbols),
    constraints (a list of expressions, or a dict name -> expression: position level when they have
    no velocity, velocity level when they have, each = 0), parameters (a dict Symbol or name ->
    value), forces (a dict coordinate -> nonconservative generalized force), initial (a dict
    coordinate or velocity -> value: q and q(t).diff(t), or qd's Symbols) and simulation (the
    [simulation] table: t_end, output_step, ...). programs (a dict name -> (expression = 0 at
    position or velocity level, actuator: a coordinate or a generalized-force vector of n
    expressions): [[programs]]), events (a dict name -> expression, or -> dict(expression=...,
    direction="rising"/"falling"/"both", action="stop"/"record"): [[events]]) and outputs (a dict
    name -> expression in t, q, q', q'', the reactions R_x and the outputs above it: [outputs]) are
    written as docs/model-format.md describes them. Returns nhdyn.Model, whose `text` is the model
    file written; nhdyn.InputError names a symbol it cannot place and what it expected."""
    sympy = _sympy()
    from . import loads

    parameters = dict(parameters or {})
    tr = _Translator(list(q), qd, list(parameters), t)
    lines = ["name = {}".format(json.dumps(name)),
             "coordinates = {}".format(json.dumps(tr.names)),
             "kinetic_energy = {}".format(json.dumps(tr(T, "T"))),
             "potential_energy = {}".format(json.dumps(tr(V if V is not None else 0, "V")))]
    if parameters:
        lines.append("\n[parameters]")
        for key, value in parameters.items():
            key_name = key.name if isinstance(key, sympy.Symbol) else str(key)
            lines.append("{} = {}".format(key_name, _value(value, "parameters[{}]".format(key_name))))
    if forces:
        lines.append("\n[forces]")
        for key, value in forces.items():
            lines.append("{} = {}".format(_name(key), json.dumps(tr(value, "forces[{}]".format(_name(key))))))
    items = constraints.items() if isinstance(constraints, dict) else (
        ("c{}".format(i + 1), c) for i, c in enumerate(constraints))
    for cname, expression in items:
        text = tr(expression, "constraint {}".format(cname))
        velocity = "'" in text
        lines += ["\n[[constraints]]", "name = {}".format(json.dumps(str(cname))),
                  "{} = {}".format("velocity" if velocity else "position", json.dumps(text))]
    lines += _programs(tr, programs)
    output_names = []
    for oname, expression in (outputs or {}).items():
        oname = _key(oname, "outputs")
        if not output_names:
            lines.append("\n[outputs]")
        text = tr(expression, "output {}".format(oname), accelerations=True,
                  extra=_reactions(tr) | set(output_names))
        lines.append("{} = {}".format(oname, json.dumps(text)))
        output_names.append(oname)
    lines += _events(tr, events, _reactions(tr) | set(output_names))
    if initial:
        position, velocity = {}, {}
        for key, value in initial.items():
            symbol = sympy.Symbol(tr(key, "initial key {}".format(key)))
            target = velocity if symbol.name.endswith("'") else position
            base = symbol.name.rstrip("'")
            if base not in tr.names:
                raise _input_error("initial: {} is not a coordinate or a coordinate's velocity".format(key))
            target[base] = json.loads(_value(value, "initial[{}]".format(key), tr))
        lines.append("\n[initial]")
        if position:
            lines.append("position = {{ {} }}".format(", ".join("{} = {}".format(k, json.dumps(v))
                                                                for k, v in position.items())))
        if velocity:
            lines.append("velocity = {{ {} }}".format(", ".join("{} = {}".format(k, json.dumps(v))
                                                                for k, v in velocity.items())))
    if simulation:
        lines.append("\n[simulation]")
        for key, value in simulation.items():
            lines.append("{} = {}".format(key, json.dumps(value)))
    return loads("\n".join(lines) + "\n", file_name)


def _speeds_in_velocities(sympy, q, u, kd_eqs, t):
    """The generalized speeds u as expressions in q and q', from the kinematic differential
    equations kd_eqs (each = 0, linear in u): u = K^-1 (-f) with K = d kd/du, through the adjugate so
    that only the determinant divides (a rotation's cos/sin give det 1, not a division by cos)."""
    if kd_eqs is None:
        raise _input_error("u: generalized speeds need kd_eqs, the kinematic differential equations (each = 0) "
                           "that give them in terms of q and q'")
    kd = sympy.Matrix([e.lhs - e.rhs if isinstance(e, sympy.Equality) else e for e in kd_eqs])
    if len(kd) != len(u):
        raise _input_error("kd_eqs: {} equations for {} generalized speeds {}; give one per speed".format(
            len(kd), len(u), ", ".join(map(_name, u))))
    K = kd.jacobian(list(u))
    f = kd.xreplace({s: 0 for s in u})
    from sympy.physics.mechanics import find_dynamicsymbols

    nonlinear = [s for s in u if s in find_dynamicsymbols(K)]
    if nonlinear:
        raise _input_error("kd_eqs are not linear in the generalized speeds {}: they cannot be solved for u; "
                           "give kinematic differential equations linear in u".format(
                               ", ".join(map(_name, nonlinear))))
    det = sympy.simplify(K.det())
    if det == 0:
        raise _input_error("kd_eqs cannot be solved for the generalized speeds {} (d kd_eqs/du is singular: "
                           "some speed is missing or two equations say the same); give one independent "
                           "equation per speed".format(", ".join(map(_name, u))))
    solution = K.adjugate() * (-f) / det
    return {s: sympy.simplify(e) for s, e in zip(u, solution)}


def _loads_as_forces(sympy, frame, loads, qd, replace, names):
    """The generalized forces of sympy.physics.mechanics loads ((Point, force) or (ReferenceFrame,
    torque) pairs, Force and Torque included): Q_j = F . dv/dq'_j, M . dw/dq'_j with the point's
    velocity and the frame's angular velocity in q' (the speeds replaced)."""
    from sympy.physics.vector import Point, ReferenceFrame, partial_velocity

    Q = [sympy.S.Zero] * len(qd)
    for i, load in enumerate(loads):
        try:
            where, vector = load
        except (TypeError, ValueError):
            raise _input_error("loads[{}]: {!r} is not a (Point, force) or (ReferenceFrame, torque) pair".format(
                i, load)) from None
        if isinstance(where, Point):
            velocity = where.vel(frame)
        elif isinstance(where, ReferenceFrame):
            velocity = where.ang_vel_in(frame)
        else:
            raise _input_error("loads[{}]: {!r} is neither a Point nor a ReferenceFrame".format(i, where))
        velocity = velocity.subs(replace)
        vector = vector.subs(replace)
        partials = partial_velocity([velocity], list(qd), frame)[0]
        for j, p in enumerate(partials):
            Q[j] += vector.dot(p)
    return {name: sympy.simplify(e) for name, e in zip(names, Q) if e != 0}


def _derived_from_configuration(sympy, holonomic, velocity, q, t):
    """The names of the velocity constraints that are time derivatives (combinations of them) of
    the configuration constraints: KanesMethod has them among its velocity_constraints to make
    u_dependent dependent, but nhdyn differentiates the position constraints itself, and twice the
    same constraint would leave its equations singular. Tested by the rank of [dc/dq', c(q' = 0)]
    at a random point (generic: an independent constraint raises the rank there)."""
    if not holonomic or not velocity:
        return set()
    import random

    import numpy as np

    qd = [c.diff(t) for c in q]
    speeds = [sympy.Dummy("v{}".format(i)) for i in range(len(q))]
    places = [sympy.Dummy("q{}".format(i)) for i in range(len(q))]
    rows = {}
    for name, e in list(holonomic.items()) + list(velocity.items()):
        e = sympy.sympify(e)
        if name in holonomic:
            e = e.diff(t)
        e = e.subs(list(zip(qd, speeds))).subs(list(zip(q, places)))
        rows[name] = list(sympy.Matrix([e]).jacobian(speeds)) + [e.xreplace({v: 0 for v in speeds})]
    free = set().union(*(sympy.Matrix([r]).free_symbols for r in rows.values())) - set(speeds)
    generator = random.Random(2718)
    point = {s: sympy.Float(generator.uniform(0.3, 1.3)) for s in free}

    def numeric(names):
        return np.array([[float(sympy.sympify(v).xreplace(point).evalf()) for v in rows[n]] for n in names])

    kept = list(holonomic)
    base = np.linalg.matrix_rank(numeric(kept), tol=1e-9)
    derived = set()
    for name in velocity:
        if np.linalg.matrix_rank(numeric(kept + [name]), tol=1e-9) == base:
            derived.add(name)
        else:
            kept.append(name)
            base += 1
    return derived


def from_sympy_mechanics(frame=None, bodies=(), q=None, u=None, kd_eqs=None, velocity_constraints=(),
                         parameters=None, *, kane=None, V=None, loads=(), configuration_constraints=(),
                         forces=None, initial=None, programs=None, events=None, outputs=None, simplify=True,
                         name="sympy_model", simulation=None, file_name="<from_sympy>"):
    """A Model from a sympy.physics.mechanics description: the inertial `frame`, the `bodies`
    (Particle, RigidBody), the coordinates q (dynamicsymbols), and optionally the generalized
    speeds u with the kinematic differential equations kd_eqs (each = 0, linear in u: they are
    solved for u in terms of q and q', so that the model is written in q'), the nonholonomic
    velocity_constraints (each = 0, in u, q and q') and the configuration_constraints (each = 0, in
    q). Or `kane=`, a KanesMethod, which gives all of these (its inertial frame, bodies, q, u,
    kinematic differential equations, velocity and configuration constraints and loads).
    T = kinetic_energy(frame, *bodies); V is the sum of the bodies' potential_energy unless given;
    loads ((Point, force) and (ReferenceFrame, torque)) become generalized forces F . dv/dq'_j
    ([forces], nonconservative: gravity given as a load runs as V would, but the energy column then
    leaves it out). simplify=False keeps SymPy's expressions as they come. The other arguments are
    those of from_sympy; programs, events and outputs may use the speeds u (replaced as in T);
    initial takes q and q(t).diff(t), not u."""
    sympy = _sympy()
    from sympy.physics import mechanics

    if kane is not None:
        if frame is not None or bodies or q is not None or u is not None or kd_eqs is not None or \
                velocity_constraints or configuration_constraints:
            raise _input_error("kane= gives the frame, bodies, q, u, kd_eqs and constraints: give them or kane, "
                               "not both")
        if getattr(kane, "_uaux", None):
            raise _input_error("kane: auxiliary speeds {} have no place in the model (they only expose "
                               "reactions in Kane's method): build the KanesMethod without u_auxiliary".format(
                                   ", ".join(map(_name, kane._uaux))))
        frame, bodies, q, u = kane._inertial, list(kane.bodies or ()), list(kane.q), list(kane.u)
        qdot = [c.diff(mechanics.dynamicsymbols._t) for c in q]
        if kane._k_ku:
            kd_eqs = list(kane._k_kqdot * sympy.Matrix(qdot) + kane._k_ku * sympy.Matrix(u) + kane._f_k)
        if kane._k_nh:
            velocity_constraints = list(kane._k_nh * sympy.Matrix(u) + kane._f_nh)
        configuration_constraints = list(kane._f_h)
        loads = loads or list(kane.loads or ())
    if frame is None or q is None:
        raise _input_error("give the inertial frame, the bodies and the coordinates q, or kane=KanesMethod(...)")
    q = list(q)
    t = mechanics.dynamicsymbols._t
    for c in q:
        if not isinstance(c, sympy.core.function.AppliedUndef):
            raise _input_error("q: {} is not a dynamicsymbol q(t) (from_sympy_mechanics works in "
                               "sympy.physics.mechanics' dynamicsymbols)".format(c))
    qd = [c.diff(t) for c in q]
    replace = _speeds_in_velocities(sympy, q, list(u), kd_eqs, t) if u is not None and len(u) else {}
    tidy = sympy.simplify if simplify else (lambda e: e)

    def in_velocities(e, what):
        e = sympy.sympify(e).subs(replace)
        left = [s for s in (u or ()) if e.has(s)]
        if left:  # pragma: no cover - replace covers every speed
            raise _input_error("{}: the speeds {} remain".format(what, left))
        return tidy(e)

    if not bodies:
        raise _input_error("bodies: give the Particle and RigidBody objects whose kinetic energy makes T")
    T = in_velocities(mechanics.kinetic_energy(frame, *bodies), "T")
    if V is None:
        V = mechanics.potential_energy(*bodies)
    V = in_velocities(V, "V")

    def named(items, prefix):
        if isinstance(items, dict):
            return {k: in_velocities(e, "constraint {}".format(k)) for k, e in items.items()}
        return {"{}{}".format(prefix, i + 1): in_velocities(e, "constraint {}{}".format(prefix, i + 1))
                for i, e in enumerate(items)}

    constraints = named(configuration_constraints, "h")
    nonholonomic = named(velocity_constraints, "nh")
    for k in _derived_from_configuration(sympy, constraints, nonholonomic, q, t):
        del nonholonomic[k]
    for k, e in nonholonomic.items():
        if k in constraints:
            raise _input_error("constraint {}: named twice".format(k))
        constraints[k] = e
    names = [_name(c) for c in q]
    all_forces = _loads_as_forces(sympy, frame, loads, qd, replace, names) if loads else {}
    for key, value in (forces or {}).items():
        key = _name(key) if not isinstance(key, str) else key
        if key not in names:
            raise _input_error("forces: {} is not a coordinate ({})".format(key, ", ".join(names)))
        all_forces[key] = all_forces.get(key, 0) + in_velocities(value, "forces[{}]".format(key))
    coordinate = dict(zip(names, q))
    # Programs, events and outputs may be written in the speeds too: they are replaced the same way.
    if replace:
        def speeds(e):
            return sympy.sympify(e).subs(replace) if isinstance(e, sympy.Basic) else e

        programs = {k: (speeds(v[0]), [speeds(e) for e in v[1]] if isinstance(v[1], (list, tuple)) else v[1])
                    if isinstance(v, (list, tuple)) and len(v) == 2 else v for k, v in (programs or {}).items()}
        events = {k: dict(v, **{key: speeds(v[key]) for key in ("expression", "when") if key in v})
                  if isinstance(v, dict) else speeds(v) for k, v in (events or {}).items()}
        outputs = {k: speeds(v) for k, v in (outputs or {}).items()}
    return from_sympy(T, V, q, constraints, parameters, forces={coordinate.get(k, k): v for k, v in all_forces.items()},
                      initial=initial, programs=programs, events=events, outputs=outputs, name=name,
                      simulation=simulation, file_name=file_name)
