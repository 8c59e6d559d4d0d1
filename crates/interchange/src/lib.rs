//! Datasets to and from other tools' files: a dataset exported as universal files (UFF 58/58b with 164 units and
//! 2411 nodes) for modal-analysis tools, and universal files written by other tools imported as a dataset.
