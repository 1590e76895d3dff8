//! Diagnosis of a bearing shake test (to come in this file).
