//! Python bindings: filled by the Python-module issue.
