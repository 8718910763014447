"""nhdyn.from_sympy: a model from SymPy expressions (sympy.physics.mechanics dynamicsymbols
included), written as the text of a model file (docs/model-format.md) and loaded as any other, so
that a SymPy user's T, V, coordinates and constraints run without rewriting them.

Each expression is printed in the model file's syntax: a coordinate q(t) becomes its name, its
derivatives q' and q''; SymPy's ** becomes ^, Abs abs, E exp(1); every other symbol must be a
parameter (given a value in `parameters`) or the time. A symbol that fits none of these is refused,
naming it and what it could have been.
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

    def __call__(self, expression, what, accelerations=False):
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
        allowed = self.known | ({n + "''" for n in self.names} if accelerations else set())
        for s in sorted(e.free_symbols, key=lambda s: s.name):
            if s.name.endswith("''") and s.name[:-2] in self.names:
                raise _input_error("{}: the acceleration {} has no place here (T, V, forces and position or velocity "
                                   "constraints depend on t, q and q' only)".format(what, s.name))
            if s.name not in allowed:
                raise _input_error(
                    "{}: cannot place the symbol {!r}: it is not a coordinate ({}), a velocity ({}), a parameter "
                    "(give its value in parameters={{{}: ...}}) or the time {}".format(
                        what, s.name, ", ".join(self.names), ", ".join(n + "'" for n in self.names), s.name,
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


def from_sympy(T, V, q, constraints=(), parameters=None, *, qd=None, forces=None, initial=None, t=None,
               name="sympy_model", simulation=None, file_name="<from_sympy>"):
    """A Model from SymPy: kinetic energy T and potential V in the coordinates q (Symbols or
    sympy.physics.mechanics dynamicsymbols q(t); with Symbols, qd lists their velocity Symbols),
    constraints (a list of expressions, or a dict name -> expression: position level when they have
    no velocity, velocity level when they have, each = 0), parameters (a dict Symbol or name ->
    value), forces (a dict coordinate -> nonconservative generalized force), initial (a dict
    coordinate or velocity -> value: q and q(t).diff(t), or qd's Symbols) and simulation (the
    [simulation] table: t_end, output_step, ...). Returns nhdyn.Model, whose `text` is the model
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
