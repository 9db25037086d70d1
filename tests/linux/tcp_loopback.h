/* SPDX-License-Identifier: Apache-2.0 */
/*
 * tests/linux/tcp_loopback.h -- a TCP listening socket on 127.0.0.1, at a port the kernel
 * chooses, for the tests that play a socketcand server.
 */
#ifndef CANOLA_TEST_TCP_LOOPBACK_H
#define CANOLA_TEST_TCP_LOOPBACK_H

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include "check.h"

/** A socket listening on 127.0.0.1 (backlog 1); its port into `*port`. */
static inline int listen_loopback(unsigned *port)
{
    int ls = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    struct sockaddr_in a = {.sin_family = AF_INET, .sin_addr.s_addr = htonl(INADDR_LOOPBACK)};
    socklen_t al = sizeof a;
    CHECK(bind(ls, (struct sockaddr *)&a, sizeof a) == 0);
    CHECK(listen(ls, 1) == 0);
    CHECK(getsockname(ls, (struct sockaddr *)&a, &al) == 0);
    *port = ntohs(a.sin_port);
    return ls;
}

#endif /* CANOLA_TEST_TCP_LOOPBACK_H */
