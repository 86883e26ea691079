// The entry point of the layer link checks (CMakeLists.txt): the layer's objects are linked
// whole around it; nothing runs.
int main() { return 0; }
