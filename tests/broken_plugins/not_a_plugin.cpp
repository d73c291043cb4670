// A shared library named like a plug-in that exports no info record.
extern "C" __attribute__((visibility("default"))) int prt_not_a_plugin() {
  return 42;
}
