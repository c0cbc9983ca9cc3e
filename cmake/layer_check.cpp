// Linked with one module's whole archive and the modules it declares, nothing else: an undefined
// reference here is a call into a module the module does not declare.
int main() {
  return 0;
}
