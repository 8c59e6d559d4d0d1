//! Datasets on disk (being written).
