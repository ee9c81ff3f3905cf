"""Forms over interface tags that change: compiled once, their facets set per tags.

An interface event changes which facets each interface integral covers (a
spring becomes an open crack), not the integrands.  ``dolfinx.fem.form`` on the
same UFL form with new tags processes the UFL again and looks the JIT cache up:
a pumped run makes thousands of forms.  :class:`TaggedForm` compiles the UFL
form once and builds the DOLFINx form for new interior-facet tags with
``dolfinx.fem.create_form``: No. 2 coarse with seepage, 120 s pumped, went from
3,400 compilations and 389 s to 9 and 327 s, the same run to every figure
(benchmarks/README.md).
"""

from __future__ import annotations

import dolfinx
import dolfinx.fem
import ufl
from dolfinx.fem import IntegralType
from dolfinx.fem.forms import get_integration_domains

_TYPES = {
    "cell": IntegralType.cell,
    "exterior_facet": IntegralType.exterior_facet,
    "interior_facet": IntegralType.interior_facet,
    "vertex": IntegralType.vertex,
}


class TaggedForm:
    """``ufl_form`` compiled once; :meth:`form` for any tags of its interior-facet integrals.

    The other integrals (cells, exterior facets) keep the subdomains they were
    built with.  A form with arguments (bilinear or linear); collective at
    construction (the compilation).
    """

    def __init__(self, ufl_form: ufl.Form) -> None:
        domain = ufl_form.ufl_domain()
        self._spaces = [arg.ufl_function_space() for arg in ufl_form.arguments()]
        self.mesh = self._spaces[0].mesh  # the Python mesh (the domain holds the C++ one)
        self.compiled = dolfinx.fem.compile_form(self.mesh.comm, ufl_form)
        self._coefficients = {c: c for c in ufl_form.coefficients()}
        self._constants = {c: c for c in ufl_form.constants()}
        data = ufl_form.subdomain_data()[domain]
        ids: dict[str, set[int]] = {kind: set() for kind in data}
        for integral in ufl_form.integrals():
            sid = integral.subdomain_id()
            if integral.subdomain_data() is None or sid == "everywhere":
                continue
            ids[integral.integral_type()].update(
                s for s in (sid if isinstance(sid, tuple) else (sid,)) if s != "everywhere"
            )
        self._ids = {kind: sorted(v) for kind, v in ids.items()}
        self._fixed = {
            _TYPES[kind]: get_integration_domains(_TYPES[kind], tags[0], self._ids[kind])
            for kind, tags in data.items()
            if kind != "interior_facet"
        }

    def form(self, tags: dolfinx.mesh.MeshTags) -> dolfinx.fem.Form:
        """Return the DOLFINx form with its interior-facet integrals over ``tags``."""
        subdomains = dict(self._fixed)
        if "interior_facet" in self._ids:
            kind = IntegralType.interior_facet
            subdomains[kind] = get_integration_domains(kind, tags, self._ids["interior_facet"])
        return dolfinx.fem.create_form(
            self.compiled, self._spaces, self.mesh, subdomains, self._coefficients, self._constants
        )


__all__ = ["TaggedForm"]
