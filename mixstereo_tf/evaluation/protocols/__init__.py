"""The registered evaluation protocols (each module registers its entries on import)."""

from mixstereo_tf.evaluation import protocol
from mixstereo_tf.evaluation.protocols import eigen  # pylint: disable=unused-import
from mixstereo_tf.evaluation.protocols import kitti  # pylint: disable=unused-import
from mixstereo_tf.evaluation.protocols import middlebury  # pylint: disable=unused-import
from mixstereo_tf.evaluation.protocols import sample  # pylint: disable=unused-import

get = protocol.get
names = protocol.names
