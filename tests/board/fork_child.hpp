#pragma once
// Runs a function in a forked child and returns its wait status: for what may only happen once per process
// (an emergency stop latches) or ends it (a signal, exit()). The child never returns into the test framework:
// it ends with _exit(the function's result) unless the function ends it first. Its checks are exit codes. A
// child still running after 20 s dies of SIGALRM, so a stop that loops for ever fails instead of hanging.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <utility>

namespace lever::test {

template <typename F>
int wait_status_of_child(F&& body) {
  std::fflush(nullptr);  // the child must not flush the parent's buffered output a second time
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    ::alarm(20);
    ::_exit(std::forward<F>(body)());
  }
  int status = 0;
  if (::waitpid(pid, &status, 0) != pid) return -1;
  return status;
}

}  // namespace lever::test
