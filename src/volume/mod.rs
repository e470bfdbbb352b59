//! The second pipeline (Chu, Jenkins, Mataric): point volumes → Isomap → nonlinear spherical
//! shells → skeleton curve → rigid bodies → joint angles. Not built yet: its issue brings it.
