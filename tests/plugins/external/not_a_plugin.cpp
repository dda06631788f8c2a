// A shared library that is not a driftlab plugin: loading it must fail clearly.
extern "C" int some_unrelated_function() { return 42; }
