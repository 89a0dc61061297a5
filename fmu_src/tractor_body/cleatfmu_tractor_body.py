"""Variable table of the tractor body FMU (native C only: ``fmu_src/native/cleatfmu_body.c``).

The body of the whole-tractor model (:mod:`identification.model.tractor`) on the
vertical forces of four tires (FL, FR, RL, RR): the rigid tractor (heave, pitch,
roll; optionally the roll of a front axle pivoting about a longitudinal pivot at
the track centre), a half tractor per side (pitch coupling only) or per axle
(roll coupling only), or four independent corners.  Per communication step it advances the scheme of
:mod:`identification.model.stepping` from the forces set at the step's start and
gives each hub's height, vertical velocity and longitudinal position for the
tire FMUs, and the hubs' and the seat's accelerations.  The build reads this
table with :mod:`ast` (nothing is imported); ``config.h`` of the native kind
must match it.  Columns: name, type, causality, variability, unit, start,
dependencies of an output (its direct feedthrough), description.
"""

START_FILE = "cleatfmu_start.txt"

VARIABLES = (
    ('force_FL', 'Real', 'input', 'continuous', 'N', 'load_FL', {}, "Vertical force of tire FL on its hub, N, compressive positive (the tire FMU's force_z)"),
    ('force_FR', 'Real', 'input', 'continuous', 'N', 'load_FR', {}, "Vertical force of tire FR on its hub, N, compressive positive (the tire FMU's force_z)"),
    ('force_RL', 'Real', 'input', 'continuous', 'N', 'load_RL', {}, "Vertical force of tire RL on its hub, N, compressive positive (the tire FMU's force_z)"),
    ('force_RR', 'Real', 'input', 'continuous', 'N', 'load_RR', {}, "Vertical force of tire RR on its hub, N, compressive positive (the tire FMU's force_z)"),
    ('load_FL', 'Real', 'parameter', 'fixed', 'N', 15000.0, {}, "Static wheel load W of tire FL, N (> 0): the body's weight share it carries at rest"),
    ('load_FR', 'Real', 'parameter', 'fixed', 'N', 15000.0, {}, "Static wheel load W of tire FR, N (> 0): the body's weight share it carries at rest"),
    ('load_RL', 'Real', 'parameter', 'fixed', 'N', 25000.0, {}, "Static wheel load W of tire RL, N (> 0): the body's weight share it carries at rest"),
    ('load_RR', 'Real', 'parameter', 'fixed', 'N', 25000.0, {}, "Static wheel load W of tire RR, N (> 0): the body's weight share it carries at rest"),
    ('static_hub_z_FL', 'Real', 'parameter', 'fixed', 'm', 0.75, {}, 'Hub height of FL at which its tire carries the static load at rest, absolute, m (z upwards)'),
    ('static_hub_z_FR', 'Real', 'parameter', 'fixed', 'm', 0.75, {}, 'Hub height of FR at which its tire carries the static load at rest, absolute, m (z upwards)'),
    ('static_hub_z_RL', 'Real', 'parameter', 'fixed', 'm', 0.75, {}, 'Hub height of RL at which its tire carries the static load at rest, absolute, m (z upwards)'),
    ('static_hub_z_RR', 'Real', 'parameter', 'fixed', 'm', 0.75, {}, 'Hub height of RR at which its tire carries the static load at rest, absolute, m (z upwards)'),
    ('wheelbase', 'Real', 'parameter', 'fixed', 'm', 2.5, {}, 'Wheelbase L, front to rear axle, m (> 0)'),
    ('pitch_index', 'Real', 'parameter', 'fixed', '1', 1.0, {}, "Pitch dynamic index: pitch inertia / (M a b), a and b the CG's distances to the axles (> 0)"),
    ('roll_index', 'Real', 'parameter', 'fixed', '1', 1.0, {}, 'Roll dynamic index: roll inertia / (M (t/2)^2), t the track width (> 0)'),
    ('pitch_coupling', 'Boolean', 'parameter', 'fixed', '', True, {}, 'Front and rear hubs of a side move as one body (heave and pitch); with roll_coupling: the whole tractor'),
    ('roll_coupling', 'Boolean', 'parameter', 'fixed', '', True, {}, 'Left and right hubs of an axle move as one body (heave and roll); with pitch_coupling: the whole tractor'),
    ('front_axle_pivot', 'Boolean', 'parameter', 'fixed', '', False, {}, 'The front axle of the whole tractor rolls about a longitudinal pivot at the track centre (needs both couplings)'),
    ('pivot_index', 'Real', 'parameter', 'fixed', '1', 0.05, {}, 'Front-axle roll index: axle roll inertia / (m_f (t/2)^2), m_f the front wheel loads / g (> 0)'),
    ('speed', 'Real', 'parameter', 'fixed', 'm/s', 1.9444444444444444, {}, "Driving speed, m/s: the hubs' longitudinal velocity"),
    ('start_x', 'Real', 'parameter', 'fixed', 'm', 0.0, {}, 'Longitudinal position of the front axle at time 0, m (rear hubs one wheelbase behind)'),
    ('seat_x', 'Real', 'parameter', 'fixed', 'm', 2.125, {}, 'Seat position behind the front axle, m'),
    ('seat_y', 'Real', 'parameter', 'fixed', '1', 0.0, {}, 'Seat position from the centre line as a fraction of the half-track (+ left)'),
    ('initial_hub_dz_FL', 'Real', 'parameter', 'fixed', 'm', 0.0, {}, "Initial displacement of hub FL from its static height, m (up); projected onto the body's motions"),
    ('initial_hub_dz_FR', 'Real', 'parameter', 'fixed', 'm', 0.0, {}, "Initial displacement of hub FR from its static height, m (up); projected onto the body's motions"),
    ('initial_hub_dz_RL', 'Real', 'parameter', 'fixed', 'm', 0.0, {}, "Initial displacement of hub RL from its static height, m (up); projected onto the body's motions"),
    ('initial_hub_dz_RR', 'Real', 'parameter', 'fixed', 'm', 0.0, {}, "Initial displacement of hub RR from its static height, m (up); projected onto the body's motions"),
    ('initial_hub_vz_FL', 'Real', 'parameter', 'fixed', 'm/s', 0.0, {}, "Initial vertical velocity of hub FL, m/s (up); projected onto the body's motions"),
    ('initial_hub_vz_FR', 'Real', 'parameter', 'fixed', 'm/s', 0.0, {}, "Initial vertical velocity of hub FR, m/s (up); projected onto the body's motions"),
    ('initial_hub_vz_RL', 'Real', 'parameter', 'fixed', 'm/s', 0.0, {}, "Initial vertical velocity of hub RL, m/s (up); projected onto the body's motions"),
    ('initial_hub_vz_RR', 'Real', 'parameter', 'fixed', 'm/s', 0.0, {}, "Initial vertical velocity of hub RR, m/s (up); projected onto the body's motions"),
    ('hub_z_FL', 'Real', 'output', 'continuous', 'm', None, {}, "Hub height of FL, absolute, m (z upwards); connect to the tire FMU's hub_z"),
    ('hub_z_FR', 'Real', 'output', 'continuous', 'm', None, {}, "Hub height of FR, absolute, m (z upwards); connect to the tire FMU's hub_z"),
    ('hub_z_RL', 'Real', 'output', 'continuous', 'm', None, {}, "Hub height of RL, absolute, m (z upwards); connect to the tire FMU's hub_z"),
    ('hub_z_RR', 'Real', 'output', 'continuous', 'm', None, {}, "Hub height of RR, absolute, m (z upwards); connect to the tire FMU's hub_z"),
    ('hub_vz_FL', 'Real', 'output', 'continuous', 'm/s', None, {}, "Hub vertical velocity of FL, m/s (up); connect to the tire FMU's hub_vz"),
    ('hub_vz_FR', 'Real', 'output', 'continuous', 'm/s', None, {}, "Hub vertical velocity of FR, m/s (up); connect to the tire FMU's hub_vz"),
    ('hub_vz_RL', 'Real', 'output', 'continuous', 'm/s', None, {}, "Hub vertical velocity of RL, m/s (up); connect to the tire FMU's hub_vz"),
    ('hub_vz_RR', 'Real', 'output', 'continuous', 'm/s', None, {}, "Hub vertical velocity of RR, m/s (up); connect to the tire FMU's hub_vz"),
    ('hub_x_FL', 'Real', 'output', 'continuous', 'm', None, {}, 'Longitudinal position of hub FL, m: start_x + speed time (- wheelbase at the rear); connect to hub_x'),
    ('hub_x_FR', 'Real', 'output', 'continuous', 'm', None, {}, 'Longitudinal position of hub FR, m: start_x + speed time (- wheelbase at the rear); connect to hub_x'),
    ('hub_x_RL', 'Real', 'output', 'continuous', 'm', None, {}, 'Longitudinal position of hub RL, m: start_x + speed time (- wheelbase at the rear); connect to hub_x'),
    ('hub_x_RR', 'Real', 'output', 'continuous', 'm', None, {}, 'Longitudinal position of hub RR, m: start_x + speed time (- wheelbase at the rear); connect to hub_x'),
    ('hub_vx', 'Real', 'output', 'continuous', 'm/s', None, {}, "Longitudinal velocity of every hub, m/s (= speed); connect to the tire FMUs' hub_vx"),
    ('hub_az_FL', 'Real', 'output', 'continuous', 'm/s2', None, {'force_FL': 'dependent', 'force_FR': 'dependent', 'force_RL': 'dependent', 'force_RR': 'dependent'}, 'Hub vertical acceleration of FL, m/s2 (up), gravity excluded, from the forces set last'),
    ('hub_az_FR', 'Real', 'output', 'continuous', 'm/s2', None, {'force_FL': 'dependent', 'force_FR': 'dependent', 'force_RL': 'dependent', 'force_RR': 'dependent'}, 'Hub vertical acceleration of FR, m/s2 (up), gravity excluded, from the forces set last'),
    ('hub_az_RL', 'Real', 'output', 'continuous', 'm/s2', None, {'force_FL': 'dependent', 'force_FR': 'dependent', 'force_RL': 'dependent', 'force_RR': 'dependent'}, 'Hub vertical acceleration of RL, m/s2 (up), gravity excluded, from the forces set last'),
    ('hub_az_RR', 'Real', 'output', 'continuous', 'm/s2', None, {'force_FL': 'dependent', 'force_FR': 'dependent', 'force_RL': 'dependent', 'force_RR': 'dependent'}, 'Hub vertical acceleration of RR, m/s2 (up), gravity excluded, from the forces set last'),
    ('seat_z', 'Real', 'output', 'continuous', 'm', None, {}, "Seat vertical displacement from its static position, m (up): the whole tractor's at the seat point; without both couplings the hubs' displacements interpolated bilinearly there"),
    ('seat_az', 'Real', 'output', 'continuous', 'm/s2', None, {'force_FL': 'dependent', 'force_FR': 'dependent', 'force_RL': 'dependent', 'force_RR': 'dependent'}, 'Seat vertical acceleration, m/s2 (up), gravity excluded, from the forces set last (as seat_z)'),
)
