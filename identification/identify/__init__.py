"""Identify: a tire's k and c from one channel of a recording.

* :mod:`~identification.identify.paper` - the cleat-test paper's method (logarithmic decrement of the
  free-vibration peaks);
* :mod:`~identification.identify.waveform` - a least-squares damped-sinusoid fit of the free decay;
* :mod:`~identification.identify.graceful` - what the data can give when the paper's rules are not met;
* :mod:`~identification.identify.static` - the static stiffness of a compression test (the paper's eq. 18).
"""

from .paper import PaperResult, identify, identify_paper

__all__ = ["PaperResult", "identify", "identify_paper"]
