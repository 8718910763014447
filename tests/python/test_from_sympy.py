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
