"""MEMS accelerometer parts for blindgen3: datasheet figures and the draw of one unit.

Figures are the typical / limit values of the public datasheets as we know them
(BMI088, ICM-42688-P, LIS2DW12, KX134-1211, ADXL362, MMA8451Q, MPU-6050). They are
rounded and meant to put a simulated unit in the right physical range, not to
reproduce any one datasheet table exactly.

Field meanings (units in the names):
  ranges_g          selectable full scales (+- g)
  bits              output word length at the finest resolution mode
  nd_ug             white noise density, micro-g per sqrt(Hz)
  odrs_hz           selectable output data rates
  bw_ratio          digital low-pass -3 dB bandwidth as a fraction of the ODR (choices)
  offset_mg         zero-g offset tolerance (+-, after board mount), mg
  sens_pct          sensitivity tolerance (+-), percent
  cross_pct         cross-axis sensitivity (+-), percent
  nonlin_pct_fs     non-linearity, percent of full scale (best-fit straight line)
  tco_mg_per_k      zero-g offset temperature coefficient (+-), mg/K
  tcs_pct_per_k     sensitivity temperature coefficient (+-), percent/K
  temp_lsb_c        temperature sensor resolution, degC per LSB (None: no temperature output)
  temp_update_hz    how often the temperature register refreshes
  odr_tol_pct       internal oscillator (ODR) tolerance (+-), percent
  self_heat_k       typical die self-heating above the board after power-up, K (range)
"""

import numpy as np

G0 = 9.80665  # standard gravity, m/s^2 (datasheets define 1 g with it)

PARTS = {
    "BMI088": dict(ranges_g=[3, 6, 12, 24], bits=16, nd_ug=175.0,
                   odrs_hz=[50, 100, 200, 400, 800], bw_ratio=[0.4, 0.2, 0.1],
                   offset_mg=20.0, sens_pct=1.0, cross_pct=0.5, nonlin_pct_fs=0.5,
                   tco_mg_per_k=0.2, tcs_pct_per_k=0.002, temp_lsb_c=0.125, temp_update_hz=0.78,
                   odr_tol_pct=1.0, self_heat_k=(0.3, 1.5)),
    "ICM-42688-P": dict(ranges_g=[2, 4, 8, 16], bits=16, nd_ug=70.0,
                        odrs_hz=[50, 100, 200, 500, 1000], bw_ratio=[0.45, 0.25, 0.1],
                        offset_mg=20.0, sens_pct=0.5, cross_pct=1.0, nonlin_pct_fs=0.1,
                        tco_mg_per_k=0.15, tcs_pct_per_k=0.005, temp_lsb_c=1 / 132.48, temp_update_hz=None,
                        odr_tol_pct=1.0, self_heat_k=(0.2, 1.0)),
    "LIS2DW12": dict(ranges_g=[2, 4, 8, 16], bits=14, nd_ug=90.0,
                     odrs_hz=[50, 100, 200, 400, 800], bw_ratio=[0.5, 0.25, 0.1, 0.05],
                     offset_mg=20.0, sens_pct=1.0, cross_pct=1.0, nonlin_pct_fs=0.5,
                     tco_mg_per_k=0.2, tcs_pct_per_k=0.01, temp_lsb_c=1 / 16, temp_update_hz=None,
                     odr_tol_pct=3.0, self_heat_k=(0.1, 0.5)),
    "KX134-1211": dict(ranges_g=[8, 16, 32, 64], bits=16, nd_ug=130.0,
                       odrs_hz=[50, 100, 200, 400, 800], bw_ratio=[0.5, 0.11],
                       offset_mg=25.0, sens_pct=1.0, cross_pct=1.0, nonlin_pct_fs=0.5,
                       tco_mg_per_k=0.2, tcs_pct_per_k=0.01, temp_lsb_c=None, temp_update_hz=None,
                       odr_tol_pct=3.0, self_heat_k=(0.2, 1.0)),
    "ADXL362": dict(ranges_g=[2, 4, 8], bits=12, nd_ug=175.0,
                    odrs_hz=[50, 100, 200, 400], bw_ratio=[0.25, 0.5],
                    offset_mg=40.0, sens_pct=10.0, cross_pct=1.0, nonlin_pct_fs=0.5,
                    tco_mg_per_k=0.5, tcs_pct_per_k=0.05, temp_lsb_c=0.065, temp_update_hz=None,
                    odr_tol_pct=10.0, self_heat_k=(0.0, 0.2)),
    "MMA8451Q": dict(ranges_g=[2, 4, 8], bits=14, nd_ug=99.0,
                     odrs_hz=[50, 100, 200, 400, 800], bw_ratio=[0.5, 0.25],
                     offset_mg=17.0, sens_pct=2.5, cross_pct=0.5, nonlin_pct_fs=0.5,
                     tco_mg_per_k=0.15, tcs_pct_per_k=0.008, temp_lsb_c=None, temp_update_hz=None,
                     odr_tol_pct=5.0, self_heat_k=(0.1, 0.6)),
    "MPU-6050": dict(ranges_g=[2, 4, 8, 16], bits=16, nd_ug=400.0,
                     odrs_hz=[50, 100, 125, 200, 250, 333.3333333333333, 500, 1000],
                     bw_ratio=[0.44, 0.2, 0.1, 0.05],
                     offset_mg=50.0, sens_pct=3.0, cross_pct=2.0, nonlin_pct_fs=0.5,
                     tco_mg_per_k=0.3, tcs_pct_per_k=0.02, temp_lsb_c=1 / 340, temp_update_hz=None,
                     odr_tol_pct=1.0, self_heat_k=(0.5, 3.0)),
}


def rot_small(v):
    """Rotation matrix of rotation vector v (rad), Rodrigues; v of shape (3,)."""
    th = float(np.linalg.norm(v))
    if th < 1e-15:
        return np.eye(3)
    k = v / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def draw_unit(rng, name=None, odr=None, coarse=False, small=False):
    """Draw one physical unit of a part: its linear errors within the datasheet tolerances
    (uniform inside +-tolerance), the configured range / ODR / bandwidth and resolution.

    Returns a dict with: part, range_g, lsb_per_g, odr_nom_hz, odr_true_hz, bw_hz,
    nd_g (white density, g/sqrt(Hz)), gain (3x3: diag(1+s) (I + C) with mounting rotation),
    offset_g (3,), and the part's datasheet figures under `ds`.
    `coarse` picks the coarsest resolution the part offers (largest range; 8-bit fast-read
    mode on the MMA8451Q), so that the LSB is larger than the noise.
    """
    if name is None:
        name = str(rng.choice(sorted(PARTS)))
    ds = PARTS[name]
    if small:
        odr_nom = 100.0
    elif odr is not None:
        odr_nom = float(odr)
    else:
        odr_nom = float(rng.choice(ds["odrs_hz"]))
    bits = ds["bits"]
    if coarse:
        rg = max(ds["ranges_g"])
        if name == "MMA8451Q":
            rg, bits = 2, 8  # F_READ: 8-bit output, 15.6 mg/LSB
        elif name == "ADXL362":
            rg = 8  # 4 mg/LSB
    else:
        rg = int(rng.choice(ds["ranges_g"][:2]))
    lsb_per_g = 2 ** (bits - 1) / rg
    bw = float(rng.choice(ds["bw_ratio"])) * odr_nom
    s = rng.uniform(-1, 1, 3) * ds["sens_pct"] / 100
    C = rng.uniform(-1, 1, (3, 3)) * ds["cross_pct"] / 100
    np.fill_diagonal(C, 0.0)
    mount = rot_small(rng.normal(0, np.radians(1.0), 3))  # die placement on the board, ~1 deg
    gain = np.diag(1 + s) @ (np.eye(3) + C) @ mount
    off = rng.uniform(-1, 1, 3) * ds["offset_mg"] / 1000
    odr_true = odr_nom * (1 + rng.uniform(-1, 1) * ds["odr_tol_pct"] / 100)
    return dict(part=name, range_g=rg, bits=bits, lsb_per_g=lsb_per_g, odr_nom_hz=odr_nom,
                odr_true_hz=odr_true, bw_hz=bw, nd_g=ds["nd_ug"] * 1e-6, gain=gain, offset_g=off,
                sens_err=s, ds=ds)
