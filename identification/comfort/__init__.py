"""Ride comfort: whole-body vibration evaluated by ISO 2631-1 (:mod:`~identification.comfort.iso2631`)."""

from .iso2631 import (CREST_FACTOR_LIMIT, EU_A8_ACTION_M_S2, EU_A8_LIMIT_M_S2, EU_VDV_ACTION, EU_VDV_LIMIT,
                      MTVV_RATIO_LIMIT, VDV_RATIO_LIMIT, WEIGHTINGS, ComfortResult, Exposure, Weighting, comfort,
                      crest_factor, daily_exposure, get_weighting, mtvv, running_rms, vdv, vdv_exposure, weight,
                      weighting_response)

__all__ = ["Weighting", "WEIGHTINGS", "get_weighting", "weighting_response", "weight", "running_rms", "mtvv",
           "vdv", "crest_factor", "daily_exposure", "vdv_exposure", "Exposure", "ComfortResult", "comfort",
           "EU_A8_ACTION_M_S2", "EU_A8_LIMIT_M_S2", "EU_VDV_ACTION", "EU_VDV_LIMIT", "CREST_FACTOR_LIMIT",
           "MTVV_RATIO_LIMIT", "VDV_RATIO_LIMIT"]
