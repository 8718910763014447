"""nhdyn.from_sympy: a SymPy user's model (sympy.physics.mechanics dynamicsymbols, or plain
Symbols with their velocities) runs without rewriting, with the results of the same model written
as a file, bit for bit; symbols it cannot place are refused, naming them and what was expected.
Model expressions read ** as a power, as SymPy prints it."""

import numpy as np
import pytest

import nhdyn

sp = pytest.importorskip("sympy")
mechanics = pytest.importorskip("sympy.physics.mechanics")


def sled_from_sympy(**overrides):
    t = sp.Symbol("t")
    x, y, phi = mechanics.dynamicsymbols("x y phi")
    m, a, rho, alpha, g = sp.symbols("m a rho alpha g")
    xd, yd, phid = (c.diff(t) for c in (x, y, phi))
    T = m / 2 * (xd**2 + yd**2) + m * a * phid * (sp.cos(phi) * yd - sp.sin(phi) * xd) + m * rho**2 / 2 * phid**2
    V = -m * g * sp.sin(alpha) * (x + a * sp.cos(phi))
    arguments = dict(T=T, V=V, q=[x, y, phi], constraints={"blade": -sp.sin(phi) * xd + sp.cos(phi) * yd},
                     parameters={m: 1, a: 0.5, rho: 0.7, alpha: sp.pi / 6, g: 9.81},
                     initial={xd: 1.0, phid: 1.0}, name="sled")
    arguments.update(overrides)
    return nhdyn.from_sympy(**arguments), (x, y, phi, xd, m, a, rho, alpha, g, T, V)


def test_dynamicsymbols_sled_is_the_model_file_bit_for_bit(examples):
    model, _ = sled_from_sympy()
    assert model.coordinates == ["x", "y", "phi"] and model.constraints == ["blade"]
    assert "alpha = \"pi/6\"" in model.text  # a SymPy constant keeps its exact value
    mine = model.simulate(t_end=5, rtol=1e-10, atol=1e-12)
    theirs = nhdyn.load(examples / "sled.toml").simulate(t_end=5, rtol=1e-10, atol=1e-12)
    assert np.array_equal(mine.t, theirs.t)
    assert np.array_equal(mine.q, theirs.q) and np.array_equal(mine.qd, theirs.qd)
    assert np.array_equal(mine.R, theirs.R) and np.array_equal(mine.energy, theirs.energy)


def test_symbols_with_velocities_and_a_position_constraint(examples):
    x, y, xd, yd, m, g, l, theta0 = sp.symbols("x y xd yd m g l theta0")
    model = nhdyn.from_sympy(m / 2 * (xd**2 + yd**2), m * g * y, [x, y], {"rod": x**2 + y**2 - l**2},
                             {m: 0.5, g: 9.81, l: 1.5, theta0: 2.0}, qd=[xd, yd],
                             initial={x: l * sp.sin(theta0), y: -l * sp.cos(theta0)}, name="pendulum-cartesian")
    options = dict(t_end=3, rtol=1e-10, atol=1e-12)
    mine = model.simulate(**options)
    theirs = nhdyn.load(examples / "pendulum_cartesian.toml").simulate(**options)
    assert np.array_equal(mine.q, theirs.q) and np.array_equal(mine.residuals, theirs.residuals)


def test_symbols_it_cannot_place_are_named():
    _, (x, y, phi, xd, m, a, rho, alpha, g, T, V) = sled_from_sympy()
    k = sp.Symbol("k")
    with pytest.raises(nhdyn.InputError, match=r"from_sympy: T: cannot place the symbol 'k': it is not a coordinate "
                                               r"\(x, y, phi\), a velocity \(x', y', phi'\), a parameter \(give its "
                                               r"value in parameters=\{k: ...\}\) or the time t"):
        sled_from_sympy(T=T + k * xd**2)
    z = mechanics.dynamicsymbols("z")
    with pytest.raises(nhdyn.InputError, match=r"V: z\(t\) is a function of time that is not a coordinate; the "
                                               r"coordinates are x, y, phi"):
        sled_from_sympy(V=V + z)
    with pytest.raises(nhdyn.InputError, match=r"constraint blade: Derivative\(x\(t\), \(t, 3\)\) is a derivative that "
                                               r"is not a coordinate's velocity"):
        sled_from_sympy(constraints={"blade": x.diff(sp.Symbol("t"), 3)})
    with pytest.raises(nhdyn.InputError, match=r"T: the acceleration x'' has no place here"):
        sled_from_sympy(T=T + xd.diff(sp.Symbol("t")) ** 2)
    with pytest.raises(nhdyn.InputError, match=r"parameters\[a\]: rho/2 is not a constant"):
        sled_from_sympy(parameters={m: 1, a: rho / 2, rho: 0.7, alpha: 0.5, g: 9.81})


def test_model_expressions_read_a_double_star_as_a_power(examples):
    text = (examples / "sled.toml").read_text()
    starred = text.replace("x'^2 + y'^2", "x'**2 + y'**2").replace("rho^2/2", "rho**2/2")
    assert starred != text
    a = nhdyn.loads(text, "sled.toml").simulate(t_end=1)
    b = nhdyn.loads(starred, "sled.toml").simulate(t_end=1)
    assert np.array_equal(a.q, b.q)


def heading_program(**overrides):
    """examples/sled_heading_program.toml from SymPy: the sled turned by a torque on phi."""
    t = sp.Symbol("t")
    x, y, phi = mechanics.dynamicsymbols("x y phi")
    m, a, rho, alpha, g, omega, v0 = sp.symbols("m a rho alpha g omega v0")
    xd, yd, phid = (c.diff(t) for c in (x, y, phi))
    T = m / 2 * (xd**2 + yd**2) + m * a * phid * (sp.cos(phi) * yd - sp.sin(phi) * xd) + m * rho**2 / 2 * phid**2
    V = -m * g * sp.sin(alpha) * (x + a * sp.cos(phi))
    arguments = dict(T=T, V=V, q=[x, y, phi], constraints={"blade": -sp.sin(phi) * xd + sp.cos(phi) * yd},
                     parameters={m: 1, a: 0.5, rho: 0.7, alpha: sp.pi / 6, g: 9.81, omega: 1, v0: 1},
                     programs={"heading": (phi - omega * t, phi)}, initial={xd: v0, phid: omega},
                     name="sled_heading_program")
    arguments.update(overrides)
    return nhdyn.from_sympy(**arguments), (x, y, phi, omega, t)


def test_a_program_from_sympy_is_the_model_file_bit_for_bit(examples):
    model, (x, y, phi, omega, t) = heading_program()
    assert "[[programs]]\nname = \"heading\"\nposition = \"phi - omega*t\"\nactuator = \"phi\"" in model.text
    options = dict(t_end=2, rtol=1e-10, atol=1e-12)
    mine = model.simulate(**options)
    theirs = nhdyn.load(examples / "sled_heading_program.toml").simulate(**options)
    assert mine.u.shape[1] == 1 and np.abs(mine.u).max() > 0.1
    for column in ("t", "q", "qd", "R", "u"):
        assert np.array_equal(getattr(mine, column), getattr(theirs, column)), column
    # The same torque as a generalized-force vector, and the program at velocity level.
    vector, _ = heading_program(programs={"heading": (phi.diff(t) - omega, [0, 0, 1])})
    assert "velocity = \"phi' - omega\"\nactuator = [\"0\", \"0\", \"1\"]" in vector.text
    assert np.allclose(vector.simulate(**options).u, mine.u, rtol=0, atol=1e-8)


def test_events_and_outputs_from_sympy_are_those_of_the_file(examples):
    x, y, xd, yd, m, g, l, theta0 = sp.symbols("x y xd yd m g l theta0")
    model = nhdyn.from_sympy(m / 2 * (xd**2 + yd**2), m * g * y, [x, y], {"rod": x**2 + y**2 - l**2},
                             {m: 0.5, g: 9.81, l: 1.5, theta0: 2.0}, qd=[xd, yd],
                             initial={x: l * sp.sin(theta0), y: -l * sp.cos(theta0)}, name="pendulum-cartesian",
                             outputs={"speed2": xd**2 + yd**2},
                             events={"bottom": x, "back": dict(expression=xd, direction="rising", action="stop"),
                                     "fast": dict(expression=sp.Symbol("speed2") - 20, direction="rising")})
    text = (examples / "pendulum_cartesian.toml").read_text() + """
[outputs]
speed2 = "x'^2 + y'^2"

[[events]]
name = "bottom"
when = "x"

[[events]]
name = "back"
when = "x'"
direction = "rising"
action = "stop"

[[events]]
name = "fast"
when = "speed2 - 20"
direction = "rising"
"""
    options = dict(t_end=5, rtol=1e-10, atol=1e-12)
    mine = model.simulate(**options)
    theirs = nhdyn.loads(text, "pendulum_cartesian.toml").simulate(**options)
    assert [e["name"] for e in mine.events] == ["fast", "bottom", "back"]
    assert [(e["name"], e["t"]) for e in mine.events] == [(e["name"], e["t"]) for e in theirs.events]
    assert np.array_equal(mine.q, theirs.q) and np.array_equal(mine.outputs["speed2"], theirs.outputs["speed2"])
    # The run stops where x' rises through 0: at the far end of the swing, half a period in.
    assert mine.t[-1] == mine.events[-1]["t"] and 1.0 < mine.t[-1] < 2.5


def knife_edge_frames():
    """A blade on a plane with sympy.physics.mechanics: frames, a RigidBody at the contact point P,
    the speeds u1 along the blade, u2 across it, u3 = phi'."""
    x, y, phi = mechanics.dynamicsymbols("x y phi")
    u1, u2, u3 = mechanics.dynamicsymbols("u1 u2 u3")
    N = mechanics.ReferenceFrame("N")
    B = N.orientnew("B", "Axis", (phi, N.z))
    B.set_ang_vel(N, u3 * N.z)
    O = mechanics.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, u1 * B.x + u2 * B.y)
    kd = [x.diff() - (u1 * sp.cos(phi) - u2 * sp.sin(phi)), y.diff() - (u1 * sp.sin(phi) + u2 * sp.cos(phi)),
          phi.diff() - u3]
    return x, y, phi, u1, u2, u3, N, B, P, kd


def test_a_chaplygin_sleigh_from_a_kanes_method(examples):
    x, y, phi, u1, u2, u3, N, B, P, kd = knife_edge_frames()
    m, a, rho, v0, w0 = sp.symbols("m a rho v0 w0")
    G = P.locatenew("G", a * B.x)
    G.v2pt_theory(P, N, B)
    sleigh = mechanics.RigidBody("sleigh", G, B, m, (mechanics.inertia(B, 0, 0, m * (rho**2 - a**2)), G))
    kane = mechanics.KanesMethod(N, [x, y, phi], [u1, u3], kd_eqs=kd, u_dependent=[u2], velocity_constraints=[u2],
                                 bodies=[sleigh])
    model = nhdyn.from_sympy_mechanics(kane=kane, parameters={m: 2, a: 0.3, rho: 0.5, v0: -1, w0: 1},
                                       initial={x.diff(): v0, phi.diff(): w0}, name="chaplygin-sleigh")
    assert model.constraints == ["nh1"] and "u1" not in model.text
    options = dict(t_end=2, rtol=1e-10, atol=1e-12)
    mine = model.simulate(**options)
    theirs = nhdyn.load(examples / "chaplygin_sleigh.toml").simulate(**options)
    # SymPy derives T (m*a*phi'*(...) expanded): the same motion to round-off. (With SymPy 1.14 it
    # is bit for bit; the tolerance leaves room for another SymPy's order of terms.)
    assert np.array_equal(mine.t, theirs.t)
    assert np.allclose(mine.q, theirs.q, rtol=0, atol=1e-12) and np.allclose(mine.qd, theirs.qd, rtol=0, atol=1e-12)


def test_a_knife_edge_from_frames_with_gravity_as_potential_or_as_a_load(examples):
    x, y, phi, u1, u2, u3, N, B, P, kd = knife_edge_frames()
    m, rho, alpha, g, v0, w = sp.symbols("m rho alpha g v0 w")
    blade = mechanics.RigidBody("blade", P, B, m, (mechanics.inertia(B, 0, 0, m * rho**2), P))
    blade.potential_energy = -m * g * sp.sin(alpha) * x
    common = dict(parameters={m: 1, rho: 0.2, alpha: sp.pi / 6, g: 9.81, v0: 1, w: 2},
                  initial={x.diff(): v0, phi.diff(): w}, name="knife-edge")
    options = dict(t_end=2, rtol=1e-10, atol=1e-12)
    theirs = nhdyn.load(examples / "knife_edge.toml").simulate(**options)
    potential = nhdyn.from_sympy_mechanics(N, [blade], [x, y, phi], [u1, u2, u3], kd, {"blade": u2}, **common)
    assert "[forces]" not in potential.text
    blade.potential_energy = 0
    load = nhdyn.from_sympy_mechanics(N, [blade], [x, y, phi], [u1, u2, u3], kd, {"blade": u2},
                                      loads=[(P, m * g * sp.sin(alpha) * N.x)], outputs={"along": u1}, **common)
    assert "[forces]\nx = \"g*m*sin(alpha)\"" in load.text
    along = load.simulate(**options)  # an output in the speed u1: the speed of P along the blade
    assert np.allclose(along.outputs["along"], np.cos(along.q[:, 2]) * along.qd[:, 0] +
                       np.sin(along.q[:, 2]) * along.qd[:, 1], rtol=0, atol=1e-12)
    for model in (potential, load):
        mine = model.simulate(**options)
        assert np.allclose(mine.q, theirs.q, rtol=0, atol=1e-12) and np.allclose(mine.R, theirs.R, rtol=0, atol=1e-12)


def test_bad_programs_events_and_speeds_are_named():
    _, (x, y, phi, omega, t) = heading_program()
    k = sp.Symbol("k")
    with pytest.raises(nhdyn.InputError, match=r"from_sympy: program heading: cannot place the symbol 'k'"):
        heading_program(programs={"heading": (phi - k * t, phi)})
    with pytest.raises(nhdyn.InputError, match=r"program heading: actuator 'omega' is not a coordinate \(x, y, phi\)"):
        heading_program(programs={"heading": (phi - omega * t, omega)})
    with pytest.raises(nhdyn.InputError, match=r"program heading: actuator \[0, 1\] is neither a coordinate \(x, y, "
                                               r"phi\) nor a generalized-force vector of 3 entries.*\(it has 2\)"):
        heading_program(programs={"heading": (phi - omega * t, [0, 1])})
    with pytest.raises(nhdyn.InputError, match=r"event turned: cannot place the symbol 'k'"):
        heading_program(events={"turned": phi - k})
    with pytest.raises(nhdyn.InputError, match=r"event turned: direction 'up' is not one of 'rising', 'falling', "
                                               r"'both'"):
        heading_program(events={"turned": dict(expression=phi - 1, direction="up")})
    x, y, phi, u1, u2, u3, N, B, P, kd = knife_edge_frames()
    blade = mechanics.RigidBody("blade", P, B, sp.Symbol("m"), (mechanics.inertia(B, 0, 0, 1), P))
    with pytest.raises(nhdyn.InputError, match=r"kd_eqs are not linear in the generalized speeds u3"):
        nhdyn.from_sympy_mechanics(N, [blade], [x, y, phi], [u1, u2, u3], kd[:2] + [phi.diff() - u3**3])
    with pytest.raises(nhdyn.InputError, match=r"kd_eqs cannot be solved for the generalized speeds u1, u2, u3"):
        nhdyn.from_sympy_mechanics(N, [blade], [x, y, phi], [u1, u2, u3], kd[:2] + [kd[0]])
    with pytest.raises(nhdyn.InputError, match=r"kd_eqs: 2 equations for 3 generalized speeds"):
        nhdyn.from_sympy_mechanics(N, [blade], [x, y, phi], [u1, u2, u3], kd[:2])


def test_a_particle_on_a_rod_from_a_kanes_method_with_a_dependent_coordinate(examples):
    """KanesMethod's configuration constraint becomes a position constraint; its derivative, which
    KanesMethod needs among the velocity constraints, is left to nhdyn (twice the same constraint
    would be singular)."""
    x, y = mechanics.dynamicsymbols("x y")
    u1, u2 = mechanics.dynamicsymbols("u1 u2")
    m, g, l, theta0 = sp.symbols("m g l theta0")
    N = mechanics.ReferenceFrame("N")
    O = mechanics.Point("O")
    O.set_vel(N, 0)
    P = O.locatenew("P", x * N.x + y * N.y)
    P.set_vel(N, u1 * N.x + u2 * N.y)
    bob = mechanics.Particle("bob", P, m)
    bob.potential_energy = m * g * y
    kane = mechanics.KanesMethod(N, [x], [u1], kd_eqs=[x.diff() - u1, y.diff() - u2], q_dependent=[y],
                                 configuration_constraints=[x**2 + y**2 - l**2], u_dependent=[u2],
                                 velocity_constraints=[x * u1 + y * u2], bodies=[bob])
    model = nhdyn.from_sympy_mechanics(kane=kane, parameters={m: 0.5, g: 9.81, l: 1.5, theta0: 2.0},
                                       initial={x: l * sp.sin(theta0), y: -l * sp.cos(theta0)})
    assert model.constraints == ["h1"]
    options = dict(t_end=2, rtol=1e-10, atol=1e-12)
    mine = model.simulate(**options)
    theirs = nhdyn.load(examples / "pendulum_cartesian.toml").simulate(**options)
    assert np.allclose(mine.q, theirs.q, rtol=0, atol=1e-12) and np.allclose(mine.R, theirs.R, rtol=0, atol=1e-12)
