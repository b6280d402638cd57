/* SPDX-License-Identifier: Apache-2.0 */
/* host-sim: the user-data flash region kept in a file, with NOR rules: erase
 * sets a page to 0xFF, a cell is programmed once between erases (programming
 * a non-erased cell fails, as STM32G0's PROGERR does), and every operation is
 * written through to the file at once, so killing the process at any moment
 * leaves the file as a power cut leaves flash. Geometry as STM32G0. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "hs_flash.h"

#define HS_PAGE_SIZE 2048u
#define HS_CELL_SIZE 8u
#define HS_PAGES 2u
#define HS_REGION (HS_PAGE_SIZE * HS_PAGES)

static uint8_t s_mem[HS_REGION];
static int s_fd = -1;

static bool prv_in_cells(uint32_t offset, uint32_t len)
{
    return offset % HS_CELL_SIZE == 0 && len % HS_CELL_SIZE == 0 && offset <= HS_REGION &&
           len <= HS_REGION - offset;
}

static bool prv_write_through(uint32_t offset, uint32_t len)
{
    return pwrite(s_fd, s_mem + offset, len, (off_t)offset) == (ssize_t)len;
}

static km_flash_result_t prv_erase(void *ctx, uint32_t page)
{
    (void)ctx;
    if (page >= HS_PAGES) {
        return KM_FLASH_ERR_ALIGN;
    }
    memset(&s_mem[(size_t)page * HS_PAGE_SIZE], 0xFF, HS_PAGE_SIZE);
    return prv_write_through(page * HS_PAGE_SIZE, HS_PAGE_SIZE) ? KM_FLASH_OK : KM_FLASH_ERR_ERASE;
}

static km_flash_result_t prv_program(void *ctx, uint32_t offset, const void *data, uint32_t len)
{
    (void)ctx;
    if (!prv_in_cells(offset, len)) {
        return KM_FLASH_ERR_ALIGN;
    }
    for (uint32_t i = 0; i < len; i++) {
        if (s_mem[offset + i] != 0xFF) {
            return KM_FLASH_ERR_PROGRAM;
        }
    }
    memcpy(s_mem + offset, data, len);
    return prv_write_through(offset, len) ? KM_FLASH_OK : KM_FLASH_ERR_PROGRAM;
}

static km_flash_result_t prv_read(void *ctx, uint32_t offset, void *data, uint32_t len)
{
    (void)ctx;
    if (offset > HS_REGION || len > HS_REGION - offset) {
        return KM_FLASH_ERR_ALIGN;
    }
    memcpy(data, s_mem + offset, len);
    return KM_FLASH_OK;
}

bool hs_flash_open(const char *path, km_flash_t *flash)
{
    s_fd = open(path, O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (s_fd < 0) {
        fprintf(stderr, "host-sim: cannot open flash file %s: %s\n", path, strerror(errno));
        return false;
    }
    struct stat st;
    fstat(s_fd, &st);
    if (st.st_size == 0) {
        /* A new part ships erased. */
        memset(s_mem, 0xFF, sizeof s_mem);
        if (!prv_write_through(0, HS_REGION)) {
            return false;
        }
    } else if (st.st_size != (off_t)HS_REGION ||
               pread(s_fd, s_mem, sizeof s_mem, 0) != (ssize_t)sizeof s_mem) {
        fprintf(stderr, "host-sim: %s is not a %u-byte flash image\n", path, HS_REGION);
        return false;
    }
    *flash = (km_flash_t){
        .page_size = HS_PAGE_SIZE,
        .prog_size = HS_CELL_SIZE,
        .page_count = HS_PAGES,
        .erase = prv_erase,
        .program = prv_program,
        .read = prv_read,
        .ctx = NULL,
    };
    return true;
}
