"""The HEAO cold-gas sizing study's figures (seed 002 §2, §3.2, §5.1), that the budget and the sweep print results beside."""

#: Seed 002 §3.2: the propellant for three worst-case sun acquisitions, lb.
STUDY_THREE_ACQUISITIONS_LB = 4.3
#: Seed 002 §5.1: the two 7.6-in tanks' load, lb.
STUDY_LOAD_LB = 4.6
#: Seed 002 §2: "The cold gas system selected will permit sun acquisition within ten minutes", min.
STUDY_ACQUISITION_MIN = 10.0
