/* A hostile course program: `hostile ATTEMPT ARG <course flags>` tries one thing a sandbox must
 * stop, and exits 0 when it got through, 3 when it was stopped, saying "stopped: REASON" on
 * stderr (a course program that renders nothing: the harness reports it as the candidate's
 * error either way).
 *
 *   write_outside PATH   create PATH (outside its folder) and write to it
 *   read_secret @PATH    read PATH (the grader's file) and copy it into its folder (the @: a
 *                        bare path in its command would have the sandbox bind its folder, as
 *                        it binds a script's)
 *   network PORT         connect to 127.0.0.1:PORT and send a line
 *   fork_bomb N          start N children that sleep (stops at the first fork that fails)
 *   daemon MARKER        leave a process behind in a session of its own (MARKER in its argv)
 *   fill_disk MIB        write MIB files of 1 MiB each into its folder
 */
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

static int stopped(void) {
    fprintf(stderr, "stopped: %s\n", strerror(errno));
    return 3;
}

static int write_outside(const char *path) {
    FILE *f = fopen(path, "w");
    if (!f) return stopped();
    fputs("escaped\n", f);
    return fclose(f) == 0 ? 0 : stopped();
}

static int read_secret(const char *path) {
    char buf[4096];
    FILE *in = fopen(path + (path[0] == '@'), "r");
    if (!in) return stopped();
    size_t n = fread(buf, 1, sizeof buf, in);
    fclose(in);
    FILE *out = fopen("stolen.txt", "w");
    if (!out) return stopped();
    fwrite(buf, 1, n, out);
    fclose(out);
    return 0;
}

static int network(const char *port) {
    int s = socket(AF_INET, SOCK_STREAM, 0);
    if (s < 0) return stopped();
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons((unsigned short)atoi(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(s, (struct sockaddr *)&a, sizeof a) != 0) return stopped();
    const char line[] = "hello from the sandbox\n";
    return write(s, line, sizeof line - 1) > 0 ? 0 : stopped();
}

static int fork_bomb(const char *count) {
    int n = atoi(count), started = 0;
    for (int i = 0; i < n; i++) {
        pid_t p = fork();
        if (p == 0) { sleep(30); _exit(0); }
        if (p < 0) break;
        started++;
    }
    int why = errno;
    printf("started %d children\n", started);
    fflush(stdout);
    errno = why;
    return started == n ? 0 : stopped();
}

static int daemon_behind(const char *marker) {
    pid_t p = fork();
    if (p < 0) return stopped();
    if (p == 0) {
        setsid();
        if (fork() == 0) {
            execl("/bin/sh", marker, "-c", "sleep 60", (char *)0);
        }
        _exit(0);
    }
    sleep(1);
    return 0;
}

static int fill_disk(const char *mib) {
    static char block[1 << 20];
    memset(block, 'x', sizeof block);
    int n = atoi(mib);
    for (int i = 0; i < n; i++) {
        char name[64];
        snprintf(name, sizeof name, "fill-%05d.bin", i);
        FILE *f = fopen(name, "w");
        if (!f) return stopped();
        if (fwrite(block, 1, sizeof block, f) != sizeof block) { fclose(f); return stopped(); }
        if (fclose(f) != 0) return stopped();
    }
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 3) return 2;
    const char *what = argv[1], *arg = argv[2];
    if (!strcmp(what, "write_outside")) return write_outside(arg);
    if (!strcmp(what, "read_secret")) return read_secret(arg);
    if (!strcmp(what, "network")) return network(arg);
    if (!strcmp(what, "fork_bomb")) return fork_bomb(arg);
    if (!strcmp(what, "daemon")) return daemon_behind(arg);
    if (!strcmp(what, "fill_disk")) return fill_disk(arg);
    return 2;
}
