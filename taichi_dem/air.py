"""Air at 300 K and 1 bar: the gas a scene's drag or heat transfer gets when it names none
(its properties defined once; VDI Heat Atlas, dry air). Plain data, for the effects' settings."""
DENSITY = 1.177              # kg/m^3
VISCOSITY = 1.846e-5         # Pa s
CONDUCTIVITY = 0.02624       # W/(m K)
HEAT_CAPACITY = 1007.0       # J/(kg K)
TEMPERATURE = 300.0          # K
