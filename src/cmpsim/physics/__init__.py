"""Floor 1, the physics kernels: pure vectorised functions, each an equation of the paper or of
a cited source (grain flow, flow factors, asperity contact, wafer geometry and kinematics,
removal laws, abrasion and two-step kinetics, materials and the films of a stack, the elastic pad stack and its
influence functions, the grooves' venting, the pad's temperature and its glazing and conditioning).

May import: numpy, scipy and the standard library only; nothing of cmpsim.
"""
