r"""Range-rate blind zones: the clutter notch of an MTI or pulse-Doppler radar."""
from __future__ import annotations

from stonesoup.base import Property

from . import _core
from ._component import ModelComponent, as_float, as_int
from .errors import ArgumentTypeError


class RangeRateNotch(ModelComponent):
    r"""A factor that takes ``inside`` where the target's radial speed relative to the
    sensor is near zero — and near each multiple of a blind speed — and ``outside``
    elsewhere.

    A target at offset :math:`\Delta p` from the sensor, moving at :math:`\Delta v`
    relative to it (its velocity less the platform's, from the pose), closes or opens at

    .. math::
        \dot r = \frac{\Delta p \cdot \Delta v}{\lVert \Delta p \rVert}.

    An MTI filter cancels :math:`|\dot r| \le w` (a boat crossing the beam, a hovering
    helicopter), decided without a square root as
    :math:`(\Delta p\cdot\Delta v)^2 \le w^2 \lVert\Delta p\rVert^2`; a pulsed MTI is also
    blind at the multiples of :math:`v_b = \lambda\,\mathrm{PRF}/2`:
    :math:`\bigl||\dot r| - k v_b\bigr| \le w`, :math:`k = 1, \dots,` ``multiples``. A
    target at the sensor has no radial speed (inside). The sensor model reads velocities at
    its ``velocity_mapping``.

    The expected P_D of a Gaussian over position and velocity integrates the notch over the
    velocity exactly: at each of the rule's position points :math:`p_k = m + L u_k`, the
    velocity is normal, :math:`N(\mu_v + B u_k,\, \Sigma_{vv} - B B^\top)` with
    :math:`B = \Sigma_{vp} L^{-\top}`, so :math:`\dot r` is normal with mean
    :math:`\mu_r` and standard deviation :math:`\sigma_r`, and the notch contributes

    .. math::
        \text{outside} + (\text{inside} - \text{outside})
        \sum_{c \in \{0, \pm v_b, \dots\}}
        \Bigl[\Phi\Bigl(\tfrac{c + w - \mu_r}{\sigma_r}\Bigr)
              - \Phi\Bigl(\tfrac{c - w - \mu_r}{\sigma_r}\Bigr)\Bigr]

    beside the other factors at :math:`p_k`. A newborn whose velocity is unknown (mean 0,
    a wide spread) is then rarely in the notch, though its mean is; P_D read at the mean
    (``pd_evaluation='mean'``) reads the notch at the mean velocity. A model holds one notch.

    A coastal radar's notch, 1.5 m/s either side of zero, blind at 32 m/s and its next two
    multiples: ``RangeRateNotch(width=1.5, blind_speed=32.0, multiples=3)``.
    """

    width: float = Property(doc="Half-width w of the notch, m/s (≥ 0).")
    blind_speed: float = Property(default=None, doc="Blind speed v_b, m/s (> 2w); None: the "
                                                    "notch at zero only.")
    multiples: int = Property(default=3, doc="How many multiples of the blind speed are "
                                             "blind (1–64).")
    inside: float = Property(default=0.0, doc="Value in the notch (default: not detected).")
    outside: float = Property(default=1.0, doc="Value elsewhere.")

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._compiled()

    def _compiled(self) -> _core.RangeRateNotch:
        def build():
            blind = None if self.blind_speed is None else as_float(self.blind_speed, "blind_speed")
            if isinstance(self.multiples, float):
                raise ArgumentTypeError("multiples", f"expected an integer, got {self.multiples!r}")
            return _core.RangeRateNotch(as_float(self.width, "width"), blind,
                                        as_int(self.multiples, "multiples", low=1, high=64),
                                        as_float(self.inside, "inside"),
                                        as_float(self.outside, "outside"))
        return self._cached("core", build)
