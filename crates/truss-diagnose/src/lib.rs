//! Diagnosis of measured trusses against simulation (under construction).
