//! The suite judged on the simulated lab: what a measurement made on the mock lab is worth against the simulated
//! truth (the Green's functions' error), the error budget, the speed/accuracy trade of the scan protocols and its
//! statistics, and the end-to-end demo with its report.
