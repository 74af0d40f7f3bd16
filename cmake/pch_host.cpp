// The translation unit the shared precompiled headers are built with (cmake/Liftd.cmake,
// liftd_add_pch_hosts); it has no code of its own.
