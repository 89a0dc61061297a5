"""The whole tractor shared by the model and co-simulation tests: wheel loads, tires, cleat and arrivals (SI)."""

TIRES = ("FL", "FR", "RL", "RR")
LOADS = (11460.0, 11600.0, 15650.0, 15510.0)
K = (550e3, 520e3, 420e3, 450e3)
C = (4200.0, 4300.0, 2400.0, 2500.0)
#: wheelbase m, speed m/s, cleat height m, cleat width m
L, V, H, W = 2.77, 7 / 3.6, 0.04, 0.10
ARRIVALS = (0.5013, 0.5013 + 0.11, 0.5013 + L / V, 0.5013 + L / V + 0.11)
