"""A recorded run, the common output of the YADE path and the reference, for cross-checks."""
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Trajectory:
    """Samples of a run: t (n,) [s]; xz (n, N, 2) disc centres [m]; block_U (n, B) block-mean
    excess pore pressure [N/m] (nan where a block holds no pore); water (n,) total water [m^2];
    balance_error (n,) relative water-balance error; info: free-form metadata."""

    t: list = field(default_factory=list)
    xz: list = field(default_factory=list)
    block_U: list = field(default_factory=list)
    water: list = field(default_factory=list)
    balance_error: list = field(default_factory=list)
    info: dict = field(default_factory=dict)

    def append(self, t, xz, block_U=(), water=np.nan, balance_error=np.nan):
        self.t.append(float(t))
        self.xz.append(np.array(xz, float))
        self.block_U.append(np.array(block_U, float))
        self.water.append(float(water))
        self.balance_error.append(float(balance_error))

    def arrays(self):
        """The samples as numpy arrays (t, xz, block_U, water, balance_error)."""
        return (np.array(self.t), np.array(self.xz), np.array(self.block_U), np.array(self.water),
                np.array(self.balance_error))
