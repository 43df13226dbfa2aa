"""Ellipse family: one public module per method (every module of this folder whose name does not start with an
underscore registers what it decorates). Importing this package imports none of them, so that
``methods.ellipse.results`` (and :mod:`methods.results`) can be imported by the method modules themselves;
:func:`methods._registry.load_builtins` imports them (:func:`methods._families.import_method_modules`)."""


def parameter_covariance(points, params, sigma: float):
    """First-order (Gauss–Markov) covariance of the ellipse parameters (xc, yc, a, b, theta) for
    isotropic noise of s.d. ``sigma`` per coordinate: sigma^2 (J^T J)^-1, J the orthogonal-distance
    Jacobian at the closest points of ``points`` on the ellipse ``params`` (Ahn et al. 2001)."""
    import numpy as np

    from methods.ellipse._geometry import orthogonal_residuals
    from methods.ellipse.orthogonal import distance_jacobian
    pts = np.asarray(points, dtype=float)
    p = np.asarray(params, dtype=float)
    _, phi = orthogonal_residuals(pts[:, 0], pts[:, 1], p)
    J = distance_jacobian(pts[:, 0], pts[:, 1], p, phi)
    return sigma ** 2 * np.linalg.inv(J.T @ J)
