/* LD_PRELOAD shim for bench/real_sitl.py: bind() of an AF_INET socket to INADDR_ANY is rewritten to 127.0.0.1, so
 * ArduPilot SITL (which listens on all addresses) stays on loopback.
 *     gcc -shared -fPIC -O2 -o bench/bind_loopback.so bench/bind_loopback.c -ldl */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <string.h>
#include <sys/socket.h>
#include <netinet/in.h>
#include <arpa/inet.h>

typedef int (*bind_fn)(int, const struct sockaddr *, socklen_t);

int bind(int fd, const struct sockaddr *addr, socklen_t len)
{
    static bind_fn real_bind;
    if (!real_bind)
        real_bind = (bind_fn)dlsym(RTLD_NEXT, "bind");
    if (addr && addr->sa_family == AF_INET && len >= (socklen_t)sizeof(struct sockaddr_in)) {
        const struct sockaddr_in *in = (const struct sockaddr_in *)addr;
        if (in->sin_addr.s_addr == htonl(INADDR_ANY)) {
            struct sockaddr_in lo;
            memcpy(&lo, in, sizeof lo);
            lo.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
            return real_bind(fd, (const struct sockaddr *)&lo, sizeof lo);
        }
    }
    return real_bind(fd, addr, len);
}
